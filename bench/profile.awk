# profile.awk - instructions per ray from the callgrind dumps of
# `build/bench_profile --profile` (bench/profile.sh runs it), split by where
# they go, and the work per ray from a -DBENCH_COUNTS build's 'profile' lines.
#
# usage: awk -f bench/profile.awk COUNTS CHAINS callgrind.out.1 callgrind.out.2 ... (in dump order)
#   COUNTS  the counting build's output (lines "profile scene variant kind library rays nodes ...");
#   CHAINS  `addr2line -a -i -f` of every address the dumps name in the bench binary: for each
#           address, the function its instruction came from, then those it was inlined into;
#   dumps   one per pass (--dump-instr=yes --compress-strings=no --compress-pos=no).
# Prints a Markdown table, one row per pass.
#
# An instruction goes to the innermost function of its inline chain that
# has a category below; generic helpers (SIMD wrappers, scalar helpers,
# compiler intrinsics) have none, so they count for what they were inlined
# into.

function category(name) {
    if (name ~ /ray_setup|slab_setup|frame_from_direction/) return "setup"
    if (name ~ /traverse|_node$|intersect_boxes|decode_rotation|far_scale|lowest_bit/) return "nodes"
    if (name ~ /hit_at|bezier_v4/) return "hit"
    if (name ~ /^hairobb_(intersect1|occluded1)|^hairobb__trace$|get_simd/) return "api"
    if (name ~ /intersect_leaf|skipped|intersect_segment|to_ray_space|power_form|horner|ribbon_f|accept|try_hit|try_end|solve_bracketed|crosses|refine|joint_at|piece|chord_pad|intersect_curve|filtered_out/) return "segments"
    return ""
}

# a compiled function's name without gcc's clone suffixes or the AVX2 copy's
function plain(name) {
    sub(/\..*$/, "", name)
    sub(/_avx2$/, "", name)
    return name
}

function where(address,    c) {
    if (object ~ /libembree/) return "embree"
    if (address in category_of) return category_of[address]
    c = category(plain(fn))
    return c == "" ? "other" : c
}

FNR == 1 { part++ }

# the passes in the order they ran: pass p is the p-th dump
part == 1 {
    if ($1 != "profile") next
    key = ++passes
    order[passes] = key
    name[key] = $2 " " $3 " " $4
    scene[key] = $2; variant[key] = $3; kind[key] = $4; library[key] = $5; rays[key] = $6
    nodes[key] = $7; leaves[key] = $8; segments[key] = $9; passed[key] = $10
    next
}

# an address, then (function, place) pairs, innermost first
part == 2 {
    if ($0 ~ /^0x/) { address = $0; sub(/^0x0*/, "", address); pending = 1; next }
    if (!pending || $0 ~ /:[0-9?]/) next   # a place, not a function
    c = category(plain($0))
    if (c != "") { category_of[address] = c; pending = 0; next }
    if (plain($0) ~ /_tracer_|^trace_block$|^trace_pass$|^parallel_for$|^worker_run$/) category_of[address] = "harness"
    next
}

# a dump: one pass
FNR == 1 { key = ""; skip_call_cost = 0 }
/^desc: Trigger: Client Request: / {
    key = part - 2
    if (substr($0, length("desc: Trigger: Client Request: ") + 1) != name[key]) mismatch[key] = 1
    next
}
/^ob=/ { object = substr($0, 4); next }
/^fn=/ { fn = substr($0, 4); next }
/^calls=/ { skip_call_cost = 1; next }
/^0x[0-9a-f]+ [0-9]+ [0-9]+/ {
    if (skip_call_cost) { skip_call_cost = 0; next }   # the call's inclusive cost: counted in the callee
    if (key == "") next
    address = $1; sub(/^0x0*/, "", address)
    cost[key, where(address)] += $3
    total[key] += $3
}

END {
    n = split("setup nodes segments hit api harness embree other", columns, " ")
    print "| scene | variant | rays | instructions/ray | / Embree's | ray set-up | nodes, traversal | leaves, segments | hit attributes | API | bench harness | inside Embree | other | nodes/ray | leaves/ray | segments/ray | passing 1st test/ray |"
    print "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    for (p = 1; p <= passes; p++) {
        k = order[p]
        if (!(k in total) || (k in mismatch)) {
            printf("| %s | %s %s | %d | %s |\n", scene[k], variant[k], kind[k], rays[k], k in mismatch ? "dump of another pass" : "no dump")
            continue
        }
        r = rays[k] > 0 ? rays[k] : 1
        base = ""
        for (q = 1; q <= passes; q++)
            if (library[order[q]] == "embree" && scene[order[q]] == scene[k] && kind[order[q]] == kind[k] && (order[q] in total) && !(order[q] in mismatch)) {
                base = order[q]; break
            }
        ratio = base == "" ? "-" : sprintf("%.2f", (total[k] / r) / (total[base] / (rays[base] > 0 ? rays[base] : 1)))
        printf("| %s | %s %s | %d | %.0f | %s", scene[k], variant[k], kind[k], rays[k], total[k] / r, ratio)
        for (c = 1; c <= n; c++) printf(" | %.0f", cost[k, columns[c]] / r)
        if (library[k] == "hairobb")
            printf(" | %.2f | %.2f | %.2f | %.2f |\n", nodes[k] / r, leaves[k] / r, segments[k] / r, passed[k] / r)
        else
            printf(" | - | - | - | - |\n")
    }
}
