# plot.gp - hairobb's run time against error chart, drawn from bench.c's TSV.
# build/bench runs it as
#   gnuplot -e "tsv='build/bench.tsv'; out='build/bench_error.png'; scenes='combed curly'; \
#               speed='primary_mrays_1t'; threads=1" bench/plot.gp
# One row of two panels per scene: Mrays/s against |t - t_ref|/r p99 (left)
# and against the hit/miss disagreement rate (right), both on log x axes.
# Rows with chart_series "hairobb" (precision variants) and "embree" (flat
# curves at each tessellation rate) are points, labelled by variant.

if (!exists("tsv")) tsv = 'build/bench.tsv'
if (!exists("out")) out = 'build/bench_error.png'
if (!exists("scenes")) scenes = 'combed'
if (!exists("speed")) speed = 'primary_mrays_1t'
if (!exists("threads")) threads = 1

rows = words(scenes)
if (strstrt(GPVAL_TERMINALS, "pngcairo") > 0) {
    set terminal pngcairo size 1400, 520 * rows font "sans,10"
} else {
    set terminal png size 1400, 520 * rows
}
set output out

set termoption noenhanced   # variant names and t_ref as written
set datafile separator "\t"
set datafile columnheaders
set logscale x
set grid
set key bottom right box opaque   # speeds start well above 0: the corner is free
set yrange [0:*]
set offsets 0, 0, graph 0.12, 0   # room above the fastest point for its label
set format x "%g"
set ylabel sprintf("primary Mrays/s, %d thread%s", threads, threads == 1 ? "" : "s")

# A log axis cannot show 0: exact zeros are drawn at the floor, which lies
# below anything measurable (one disagreement in 16384 rays is 0.006 %).
dt_floor = 1e-9
disagree_floor = 1e-4
floored(x, f) = (x > f ? x : f)
in_series(scene, series) = (strcol("scene") eq scene && strcol("chart_series") eq series)
x_of(scene, series, name, f) = in_series(scene, series) ? floored(column(name), f) : NaN
on_chart(scene) = (strcol("scene") eq scene && strcol("chart_series") ne "-")
x_any(scene, name, f) = on_chart(scene) ? floored(column(name), f) : NaN

# Variants of equal accuracy share an x: consecutive rows put their labels
# above, to the right of and below their points so that they stay legible.
label_of(k) = (int($0) % 3 == k ? strcol("variant") : "")

set multiplot layout rows, 2
do for [i = 1:rows] {
    sc = word(scenes, i)
    do for [panel = 1:2] {
        name = panel == 1 ? "dt_r_p99" : "disagree_pct"
        f = panel == 1 ? dt_floor : disagree_floor
        set xlabel panel == 1 ? "|t - t_ref| / r, 99th percentile (log)" : "hit/miss disagreement with the reference, % (log; 0 drawn at 1e-4)"
        # pad the x range by a factor of 3 each way so that no point sits on
        # the frame and a single x value still gives a range
        stats tsv using (x_any(sc, name, f)) nooutput
        set xrange [STATS_min / 3.0 : STATS_max * 3.0]
        set title sprintf("%s: run time against %s", sc, panel == 1 ? "distance error" : "hit/miss errors")
        plot tsv using (x_of(sc, "hairobb", name, f)):(column(speed)) with points pt 7 ps 1.5 lc rgb "#1f77b4" title "hairobb", \
             tsv using (x_of(sc, "hairobb", name, f)):(column(speed)):(label_of(0)) with labels center offset 0, 1 tc rgb "#1f77b4" notitle, \
             tsv using (x_of(sc, "hairobb", name, f)):(column(speed)):(label_of(1)) with labels left offset 1.2, 0 tc rgb "#1f77b4" notitle, \
             tsv using (x_of(sc, "hairobb", name, f)):(column(speed)):(label_of(2)) with labels center offset 0, -1 tc rgb "#1f77b4" notitle, \
             tsv using (x_of(sc, "embree", name, f)):(column(speed)) with points pt 5 ps 1.5 lc rgb "#d62728" title "Embree flat", \
             tsv using (x_of(sc, "embree", name, f)):(column(speed)):(label_of(0)) with labels center offset 0, 1 tc rgb "#d62728" notitle, \
             tsv using (x_of(sc, "embree", name, f)):(column(speed)):(label_of(1)) with labels left offset 1.2, 0 tc rgb "#d62728" notitle, \
             tsv using (x_of(sc, "embree", name, f)):(column(speed)):(label_of(2)) with labels center offset 0, -1 tc rgb "#d62728" notitle
    }
}
unset multiplot
