# plot.gp - hairobb's run time against error chart, drawn from the bench's
# TSV (bench/tsv_chart.c; gnuplot 5.2 or later). build/bench runs it as
#   gnuplot -e "tsv='build/bench.tsv'; out='build/bench_error.png'; scenes='combed curly'; \
#               speed='primary_mrays_1t'; threads=1" bench/plot.gp
# One row of two panels per scene: Mrays/s against |t - t_ref|/r p99 (left)
# and against the hit/miss disagreement rate (right), both on log x axes.
# Rows with chart_series "hairobb" (precision variants) and "embree" (flat
# curves at each tessellation rate) are points, each labelled with its
# variant; "hairobb-round" and "embree-round" (round curves: tubes, their
# errors against the tube reference, not the ribbon's) are triangles in the
# same colours, named in the key as tubes. An exact 0 is drawn at a floor,
# marked by a dashed line and a note that says what a point on it means.
#
# Variants of equal accuracy share an x, and in the hit/miss panel every
# variant without a disagreement sits at the floor: so each label takes the
# first place (beside its point, above, below, then a line or more up or
# down with a leader) that no other label, point, the key or the note covers.

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

set termoption noenhanced   # variant names and t_ref as written
set datafile separator "\t"
set datafile columnheaders
set logscale x
set grid
set key bottom right box opaque   # speeds start well above 0: the corner is free
set format x "%g"
set style textbox opaque noborder   # the floor's note, should the floor's line cross it
set ylabel sprintf("primary Mrays/s, %d thread%s", threads, threads == 1 ? "" : "s")
# fixed margins (characters), so that every panel's plot area is the one measured here
set lmargin 10
set rmargin 3
set tmargin 2.5
set bmargin 4

# A character and a point's marker in graph units (fractions of the plot
# area), measured on an empty panel of the same layout.
set output '/dev/null'
set multiplot layout rows, 2
plot [1:10] [0:1] 2 notitle
# (the plot area is given in pixels, a character in terminal units: SCALE a pixel)
pixel = exists("GPVAL_TERM_SCALE") ? 1.0 * GPVAL_TERM_SCALE : 1.0
plot_width = pixel * (GPVAL_TERM_XMAX - GPVAL_TERM_XMIN)
plot_height = pixel * (GPVAL_TERM_YMAX - GPVAL_TERM_YMIN)
char_w = GPVAL_TERM_HCHAR / plot_width
char_h = GPVAL_TERM_VCHAR / plot_height
mark_w = 0.5 * GPVAL_TERM_VCHAR / plot_width   # ps 1.5: about a character high
mark_h = 0.5 * GPVAL_TERM_VCHAR / plot_height
unset multiplot
set output out

# A log axis cannot show 0: exact zeros are drawn at the floor, which lies
# below anything measurable (one disagreement in 16384 rays is 0.006 %).
dt_floor = 1e-9
disagree_floor = 1e-4
measured(x) = (x == x)   # not NaN (a variant not measured)
floored(x, f) = (x > f ? x : f)
in_series(scene, series) = (strcol("scene") eq scene && strcol("chart_series") eq series)
x_of(scene, series, name, f) = in_series(scene, series) && measured(column(name)) ? floored(column(name), f) : NaN
# hairobb filled circles, Embree open squares: a point of each at one place
# shows both; their tubes filled and open triangles
hairobb_colour = "#1f77b4"
embree_colour = "#d62728"
# the series by chart_series, and each one's title in the key
series_of(name) = name eq "hairobb" ? 1 : name eq "embree" ? 2 : name eq "hairobb-round" ? 3 : 4
array SERIES_TITLE[4] = ["hairobb", "Embree flat", "hairobb tubes (tube ref.)", "Embree round (tube ref.)"]
array SHOWN[4]   # the series with a point in the panel drawn
key_title(series) = SHOWN[series] ? SERIES_TITLE[series] : ""

# A panel's points: data and graph coordinates, variant, series (1 hairobb,
# 2 Embree, 3 hairobb's tubes, 4 Embree's tubes: series_of).
MAX_POINTS = 32
array X[MAX_POINTS]
array Y[MAX_POINTS]
array GX[MAX_POINTS]
array GY[MAX_POINTS]
array NAME[MAX_POINTS]
array SERIES[MAX_POINTS]
# Boxes taken on the panel (graph units): the points' markers, the key, the
# floor's note, and each label as it is placed.
MAX_BOXES = 3 * MAX_POINTS
array BX0[MAX_BOXES]
array BX1[MAX_BOXES]
array BY0[MAX_BOXES]
array BY1[MAX_BOXES]
take(x0, x1, y0, y1) = (boxes = boxes + 1, BX0[boxes] = x0, BX1[boxes] = x1, BY0[boxes] = y0, BY1[boxes] = y1, boxes)
# Whether a line of text width wide, from x0, centred at height y, lies in
# the panel clear of every box taken.
overlaps(x0, x1, y0, y1) = sum [b = 1:boxes] (x1 < BX0[b] || x0 > BX1[b] || y1 < BY0[b] || y0 > BY1[b] ? 0 : 1)
free(x0, y, width) = x0 >= 0 && x0 + width <= 1 && y - 0.5 * char_h >= 0 && y + 0.5 * char_h <= 1 && \
                     overlaps(x0, x0 + width, y - 0.5 * char_h, y + 0.5 * char_h) == 0
take_text(x0, y, width) = take(x0, x0 + width, y - 0.5 * char_h, y + 0.5 * char_h)
# Where a label may go, in the order tried: its side (1 right of the point,
# -1 left, 0 centred on it) and its centre's height above the point in lines.
array SIDE[16] = [1, -1, 0, 0, 1, 1, -1, -1, 1, 1, -1, -1, 1, 1, -1, -1]
array LINES[16] = [0, 0, 1.2, -1.2, 1, -1, 1, -1, 2, -2, 2, -2, 3, -3, 3, -3]
label_anchor(p, side) = GX[p] + side * (mark_w + 0.5 * char_w)
label_x0(p, side, width) = label_anchor(p, side) - (side == 1 ? 0 : side == -1 ? width : width / 2)
label_y(p, c) = GY[p] + LINES[c] * char_h
# Where the floor's note may go, in the order tried: right of the floor's
# line (1), left of it (-1), or as near it as the panel allows (0), and its
# centre's height in lines (the last three above the key: set per panel,
# the key being a line a series shown and 1.5 more).
array NOTE_SIDE[5] = [1, -1, 1, -1, 0]
array NOTE_LINES[5] = [1.2, 1.2, 4.7, 4.7, 4.7]
note_x(side) = side == 1 ? floor_x + char_w : side == -1 ? floor_x - char_w - width : \
               (floor_x + char_w + width <= 1 ? floor_x + char_w : 1 - width)
add_point(x, y) = (points = points + 1, X[points] = x, Y[points] = y, NAME[points] = strcol("variant"), \
                   SERIES[points] = series_of(strcol("chart_series")), \
                   accuracy_rays = column("accuracy_rays"), 0)

set multiplot layout rows, 2
do for [i = 1:rows] {
    sc = word(scenes, i)
    do for [panel = 1:2] {
        name = panel == 1 ? "dt_r_p99" : "disagree_pct"
        f = panel == 1 ? dt_floor : disagree_floor
        set xlabel panel == 1 ? "|t - t_ref| / r, 99th percentile (log)" : "hit/miss disagreement with the reference, % (log)"
        set title sprintf("%s: run time against %s", sc, panel == 1 ? "distance error" : "hit/miss errors")
        points = 0
        stats tsv using (strcol("scene") eq sc && strcol("chart_series") ne "-" && measured(column(name)) && \
                         measured(column(speed)) && points < MAX_POINTS ? add_point(floored(column(name), f), column(speed)) : 0) nooutput
        if (points == 0) {   # no figure to draw (nothing compared): an empty panel that says so
            set xrange [1 : 10]
            set yrange [0 : 1]
            set label 1 "no accuracy figures" at graph 0.5, graph 0.5 center
            plot 2 notitle
        } else {
            # the x range padded by a factor of 3 each way, so that no point sits
            # on the frame and a single x value still gives a range; the y range
            # from 0 to a round number above the fastest point
            x_min = X[1]
            x_max = X[1]
            y_max = Y[1]
            do for [p = 2:points] {
                x_min = X[p] < x_min ? X[p] : x_min
                x_max = X[p] > x_max ? X[p] : x_max
                y_max = Y[p] > y_max ? Y[p] : y_max
            }
            x_min = x_min / 3.0
            x_max = x_max * 3.0
            y_step = 10 ** floor(log10(y_max * 1.1)) / 2.0
            y_top = ceil(y_max * 1.1 / y_step) * y_step
            set xrange [x_min : x_max]
            set yrange [0 : y_top]

            boxes = 0
            do for [p = 1:points] {
                GX[p] = log(X[p] / x_min) / log(x_max / x_min)
                GY[p] = Y[p] / y_top
                dummy = take(GX[p] - mark_w, GX[p] + mark_w, GY[p] - mark_h, GY[p] + mark_h)
            }
            # the key: a line a series shown, as wide as its longest title and the sample
            do for [series = 1:4] { SHOWN[series] = 0 }
            do for [p = 1:points] { SHOWN[SERIES[p]] = 1 }
            key_lines = 0
            key_chars = 0
            do for [series = 1:4] {
                key_lines = key_lines + SHOWN[series]
                key_chars = SHOWN[series] && strlen(SERIES_TITLE[series]) > key_chars ? strlen(SERIES_TITLE[series]) : key_chars
            }
            key_h = key_lines + 1.5
            dummy = take(1 - (key_chars + 10) * char_w, 1, 0, key_h * char_h)
            do for [c = 3:5] { NOTE_LINES[c] = key_h + 1.2 }
            # what a point at the floor means, beside a dashed line at the floor
            floor_x = log(f / x_min) / log(x_max / x_min)
            at_floor = 0
            do for [p = 1:points] { at_floor = at_floor || X[p] == f }
            if (at_floor) {
                note = panel == 1 ? "on this line: |t - t_ref| / r = 0" : sprintf("on this line: 0 of %d rays disagree", accuracy_rays)
                set arrow 1 from graph floor_x, graph 0 to graph floor_x, graph 1 nohead dt 2 lc rgb "gray50" back
                # beside the line at the bottom (right, left), else above the key, else
                # above the key as near the line as the panel allows
                width = (strlen(note) + 1) * char_w
                placed = 0
                do for [c = 1:|NOTE_SIDE|] {
                    placed = !placed && free(note_x(NOTE_SIDE[c]), NOTE_LINES[c] * char_h, width) ? c : placed
                }
                placed = placed ? placed : |NOTE_SIDE|
                set label 1 note at graph note_x(NOTE_SIDE[placed]), graph NOTE_LINES[placed] * char_h left tc rgb "gray30" front boxed
                dummy = take_text(note_x(NOTE_SIDE[placed]), NOTE_LINES[placed] * char_h, width)
            }

            do for [p = 1:points] {
                width = (strlen(NAME[p]) + 1) * char_w
                placed = 0
                do for [c = 1:|SIDE|] {
                    placed = !placed && free(label_x0(p, SIDE[c], width), label_y(p, c), width) ? c : placed
                }
                placed = placed ? placed : 1   # nowhere free: beside the point, over what is there
                side = SIDE[placed]
                dummy = take_text(label_x0(p, side, width), label_y(p, placed), width)
                colour = SERIES[p] % 2 == 1 ? hairobb_colour : embree_colour
                set label p + 1 NAME[p] at graph label_anchor(p, side), graph label_y(p, placed) tc rgb colour front
                if (side == 1) { set label p + 1 left }
                if (side == -1) { set label p + 1 right }
                if (side == 0) { set label p + 1 center }
                if (side != 0 && LINES[placed] != 0) {   # a leader from the point to its label
                    set arrow p + 1 from graph GX[p], graph GY[p] to graph label_anchor(p, side), graph label_y(p, placed) \
                        nohead lw 0.5 lc rgb colour back
                }
            }

            # a series without a point in this panel is left out of the key (an empty title)
            plot tsv using (x_of(sc, "hairobb", name, f)):(column(speed)) with points pt 7 ps 1.5 lc rgb hairobb_colour title key_title(1), \
                 tsv using (x_of(sc, "embree", name, f)):(column(speed)) with points pt 4 ps 1.5 lw 2 lc rgb embree_colour title key_title(2), \
                 tsv using (x_of(sc, "hairobb-round", name, f)):(column(speed)) with points pt 9 ps 1.6 lc rgb hairobb_colour title key_title(3), \
                 tsv using (x_of(sc, "embree-round", name, f)):(column(speed)) with points pt 8 ps 1.6 lw 2 lc rgb embree_colour title key_title(4)
        }
        unset label
        unset arrow
    }
}
unset multiplot
