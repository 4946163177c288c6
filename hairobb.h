/* hairobb.h - v0.2.0 - ray tracing of hair and fur with a mixed AABB/OBB BVH
   single-file C library, public domain or MIT (see the end of the file)

   Builds a 4-wide (or 8-wide) bounding volume hierarchy over cubic hair
   segments and intersects rays with them exactly. Groups of neighbouring
   hairs point the same way, so boxes oriented along the hair ("hair
   space") bound them far more tightly than axis-aligned boxes; the builder
   decides per node, by the surface area heuristic, whether an axis-aligned
   (AABB) or an oriented (OBB) node pays (Woop, Benthin, Wald, Johnson,
   Tabellion, HPG 2014). Nodes are stored compressed (byte rotations and
   byte boxes), the build runs on all cores, and the buffers are Embree's
   curve buffers. Speed, memory and accuracy figures are in
   docs/benchmarking.md and docs/accuracy.md, each from a named run; this
   manual describes behaviour.

   MANUAL
      1. QUICK START
      2. API MAP
      3. CONFIGURATION MACROS
      4. INPUT and MEMORY LIFETIME
      5. THE SURFACE
      6. HITS
      7. BUILD OPTIONS
      8. THREADS and BUILD MEMORY
      9. REFIT
     10. MOTION BLUR
     11. SCENES (several hair groups, instances)
     12. .hair FILES
     13. SAVE AND LOAD
     14. SIMD PATHS
     15. THREAD SAFETY
     16. ERRORS
     17. SECTIONS OF THIS FILE
   Stop after 2 if you only want the API; each declaration below the manual
   says what it takes and returns.


   1. QUICK START
   --------------
     In exactly one C or C++ file:
         #define HAIROBB_IMPLEMENTATION
         #include "hairobb.h"
     Everywhere else just #include "hairobb.h".

     float    vertices[] = { x,y,z,radius, x,y,z,radius, ... };  // 4 floats a control point
     uint32_t indices[]  = { 0, 4, 8, ... };          // first control point of each segment
     hairobb_bvh *bvh;
     hairobb_result res = hairobb_build(vertices, vertex_count, indices, segment_count,
                                        NULL, &bvh);           // NULL: default options
     if (res != HAIROBB_OK) { puts(hairobb_result_string(res)); return 1; }
     hairobb_ray ray = { {0,0,-5}, 0.0f, {0,0,1}, INFINITY, 0.0f };  // org, tnear, dir, tfar, time
     hairobb_hit hit;
     if (hairobb_intersect1(bvh, &ray, &hit)) printf("segment %u at t=%g\n", hit.prim_id, hit.t);
     hairobb_free(bvh);

     A zero-initialised hairobb_build_options means the defaults (in C++:
     hairobb_build_options o = hairobb_default_options(); or = {}). Keep
     vertices and indices alive and unchanged until hairobb_free, or as
     MEMORY LIFETIME allows (a static BVH with its copy that is only
     traced may free them after the build). A .hair file gives the same buffers (.hair FILES):
         hairobb_hair hair;
         hairobb_hair_load("straight.hair", NULL, &hair);
         hairobb_build(hair.vertices, hair.vertex_count, hair.indices, hair.segment_count,
                       NULL, &bvh);
         ... trace ..., hairobb_free(bvh), then hairobb_hair_free(&hair).


   2. API MAP
   ----------
     Build and free
       hairobb_default_options  the default build options (a zeroed struct; C and C++)
       hairobb_check_options    the name of the first option out of range, or NULL
       hairobb_build            a BVH over the caller's segments (options may be NULL)
       hairobb_free             frees a BVH (NULL is ignored)
     Trace
       hairobb_intersect1       the nearest hit in [tnear, tfar], or a miss
       hairobb_occluded1        whether anything is hit in [tnear, tfar]; stops at the first hit
       hairobb_intersect1_from  a secondary ray leaving an earlier hit (HITS)
       hairobb_occluded1_from   a shadow ray leaving an earlier hit (HITS)
       hairobb_intersect1_context  intersect1(_from) with a per-call hit filter and its data (HITS)
       hairobb_occluded1_context   occluded1(_from) with a per-call hit filter and its data (HITS)
     Several hair groups (SCENES)
       hairobb_build_groups     one BVH over several groups' arrays (masks, user pointers; hit.group_id)
       hairobb_refit_group      new positions of one group of such a BVH
       hairobb_load_groups      such a BVH from saved bytes, over the same groups
       hairobb_group_count      its group count (1 for hairobb_build's BVHs)
       hairobb_group_user       a group's user pointer
       hairobb_group_segments   a group's segment count
       hairobb_get_group_stats  each group's segments, points, leaf references, bytes and shape
       hairobb_scene_build      a top level over instances of BVHs (maps, masks, user pointers)
       hairobb_scene_update     new maps, masks, users or BVHs for the same instances
       hairobb_scene_free       frees a scene (not its BVHs; NULL is ignored)
       hairobb_scene_user       an instance's user pointer
       hairobb_scene_count      its instance count
       hairobb_scene_bounds     the world bounds of its instances
       hairobb_scene_memory_bytes  the bytes it allocated (not its BVHs')
       hairobb_scene_intersect1 the nearest hit over every instance, hit->instance_id which
       hairobb_scene_occluded1  whether any instance is hit
     Move the hair
       hairobb_refit            the same segments at new positions (REFIT)
       hairobb_refit_tangents   the same for Hermite segments, with new tangents
       hairobb_refit_motion     new arrays for every time step of a moving BVH (MOTION BLUR)
     Save and load (SAVE AND LOAD)
       hairobb_save_size        the bytes hairobb_save writes
       hairobb_save             the BVH into a buffer
       hairobb_load             a BVH from saved bytes, over the same hair
       hairobb_save_file        hairobb_save into a file (not with HAIROBB_NO_STDIO)
       hairobb_load_file        hairobb_load from a file (not with HAIROBB_NO_STDIO)
     .hair files (.hair FILES)
       hairobb_hair_read        Cem Yuksel's format from memory
       hairobb_hair_load        the same from a file (not with HAIROBB_NO_STDIO)
       hairobb_hair_free        frees what the two above allocated
     Inspect
       hairobb_memory_bytes     every byte the BVH allocated
       hairobb_get_stats        node and leaf counts, depth, bytes, SAH cost now and as built
       hairobb_bounds           the bounds of all ribbons, radius included
       hairobb_interpolate      position, radius and derivatives at a hit's (group, prim, u)
       hairobb_basis_weights    the control points' weights at u: the caller's own per-vertex data
       hairobb_get_simd         the instruction set the BVH traces with (SIMD PATHS)
       hairobb_simd_string      its name
       hairobb_result_string    the name of a result code (ERRORS)


   3. CONFIGURATION MACROS
   -----------------------
     Define before including the implementation.
     HAIROBB_MALLOC(size, user), HAIROBB_FREE(ptr, user)   allocation; define
                             both or neither. user = options->allocator_user.
                             The build calls them from its threads at once
                             (THREADS): they must be thread-safe.
     HAIROBB_ASSERT(x)       internal checks, default assert().
     HAIROBB_STATIC          make every function static to the including file.
     HAIROBB_NO_SIMD         plain C everywhere (same answers as the SIMD paths).
     HAIROBB_NO_STDIO        leave out hairobb_hair_load, hairobb_save_file and
                             hairobb_load_file (no <stdio.h>).
     HAIROBB_NO_THREADS      build on the calling thread only. Otherwise the
                             build uses Win32 threads on Windows (Vista and
                             later; the implementation includes <windows.h>,
                             lean and without min/max macros), and pthreads
                             on POSIX systems: link with -pthread (glibc 2.34
                             and later need nothing). Elsewhere it runs on
                             the calling thread, or on options.parallel_for.
     HAIROBB_NO_DISPATCH     no AVX2 copy of the kernels (SIMD PATHS).
     HAIROBB_NO_HUGE_PAGES   no madvise(MADV_HUGEPAGE). Otherwise, on Linux
                             where <sys/mman.h> declares it (glibc or musl
                             with _DEFAULT_SOURCE or _GNU_SOURCE, as C++ and
                             gcc's gnu modes have; not strict -std=c99 alone),
                             blocks of 4 MB and more that a build or a load
                             allocates (node memory, leaf ids, the build's
                             per-segment arrays) are advised to take 2 MB
                             pages where the kernel has transparent huge
                             pages in its "madvise" mode: far fewer page
                             faults while a build first writes them.
     HAIROBB_SELF            the file's name as the runtime dispatch includes
                             it again, default "hairobb.h": the name relative
                             to the header's own folder (a quoted #include
                             looks there first), so define it where the
                             file is renamed, not where it is moved.
     HAIROBB_NODE_WIDTH      children per node, 4 or 8; default 8 where the
                             compiler targets AVX or the AVX2 copy is
                             compiled in, else 4.


   4. INPUT and MEMORY LIFETIME
   ----------------------------
     INPUT: the vertex and index layout is Embree's curve layout, so a
     renderer can hand the same buffers to either library: vertices are 4
     floats per control point (x, y, z, radius), indices[i] is the first of
     the 4 consecutive control points of segment i. Position and radius are
     cubic Bezier curves in u. No alignment is required. Other curve bases
     (B-spline, Catmull-Rom, Hermite, linear) are options.basis
     (BUILD OPTIONS). Coordinates, radii (and Hermite tangents) must be
     finite and at most 1e18 in magnitude, radii at least 0: anything
     else is INVALID_GEOMETRY (ERRORS).

     MEMORY LIFETIME: by default (bezier_copy, BUILD OPTIONS) a static BVH
     traces its own copy of every segment's Bezier points and never reads
     the caller's arrays while tracing. Other bases: the BVH keeps a copy
     of the indices too, and the caller's arrays may go after the build.
     Bezier input: hairobb_save hashes the copy, and the caller's arrays
     may go after the build too, except for hairobb_refit, which indexes
     the indices given to the build: a renderer that refits Bezier input
     keeps the index array alive and unchanged until hairobb_free. With
     bezier_copy OFF, and for moving hair,
     the BVH reads the caller's arrays (tangents too) while tracing: they
     must stay alive and unchanged until hairobb_free. To move the hair,
     refit (REFIT) or build again.


   5. THE SURFACE
   --------------
     Each segment is a ray-facing ribbon (Embree's "flat" curve). In ray space
     (origin at the ray origin, z along the normalised direction) let P(u) and
     r(u) be the segment's position and radius and P2 = (x, y) the projection.
     The ribbon is hit at u in [0,1] where dot(P2(u), P2'(u)) = 0 and
     |P2(u)| <= r(u); t = z(u)/|dir| (org + t*dir is on the curve's centre line).
     The first hit is the smallest t in [tnear, tfar] over all segments
     (of segments hit at the same t, the one with the smallest index).
     Where float rounding leaves a ray at a smooth joint of a strand (the
     next segment in index order starts where one ends, tangents parallel)
     with no root in either segment, the joint point counts as a hit on
     the segment whose end it is: strands are watertight at their joints.
     v in [-1,1] is the signed position across the ribbon:
       v = dot(cross(T, X - C), dir/|dir|) / (|T_perp| r(u)),
     T = P'(u), C = P(u), X = org + t*dir, T_perp = T without its component
     along dir. The default intersector finds the roots of dot(P2, P2') with a
     bracketed Newton iteration after a conservative test against 8 linear
     pieces, so its hits agree with this definition up to float rounding.
     docs/accuracy.md says how that is measured.
     Round curves (options.shape = HAIROBB_SHAPE_ROUND) are tubes instead:
     at each u a circle of radius r(u) about P(u) in the plane normal to
     P'(u) (Embree's cubic round curves; not a sweep of spheres, which is
     fatter where the radius tapers). There is no circle where P'
     vanishes (|P'| under 2^-12 of 3 times the control polygon's longest
     leg, or under 16 FLT_EPSILON of the largest |coordinate|): a zero-length
     segment (every point equal, in any basis) has no tube, and a cusp or
     a repeated control point leaves no surface at that u. The ends are
     open, as Embree's;
     options.end_caps = HAIROBB_ON closes each free end with a flat cap,
     the disk of radius r normal to P' there, whose hits report u exactly 0
     or 1 and Ng = -P'(0) or P'(1), unit. An end is free where it is no
     smooth joint with the neighbouring segment in index order (segment
     i - 1 or i + 1 of the indices array: the same point, tangents
     parallel within 1e-3): a strand's tips, and both sides of a kink.
     Joints follow the index order, not the vertex order: a strand whose
     segments are listed out of order (indices {8, 0, 4} for Bezier
     segments at vertices 0, 4, 8 in a row) gets caps inside it where
     neighbours in the list do not meet; list each strand's segments in
     order along it. Both sheets count:
     a ray meets the entry at t = (z(u) - S)/|dir| and the exit at (z(u) +
     S)/|dir|, S = sqrt(r^2 - |P2|^2), where the circle's plane meets the
     ray on the circle. The intersector finds the intervals of u where the
     ray passes within r of the centre line, then each sheet's roots in
     them from sign changes at samples, refined by Newton steps kept in
     the bracket (halving where a step leaves it); a ray within about 1e-3 r of a
     tube's silhouette is decided by the float rounding of the points in
     ray space. options.back_faces = HAIROBB_OFF keeps only hits whose
     normal faces the ray (entries; a ray inside a fibre does not see it).
     Round curves take the exact precision only (PIECES:
     INVALID_ARGUMENT).


   6. HITS
   -------
     hairobb_hit: t, u, v as above; Ng the ribbon's unit normal facing the ray
     origin (round curves: the tube's outward unit normal, with the
     curvature term, n ~ R - r r' P' / (|P'|^2 - R.P''), R = X - P(u));
     tangent = P'(u) in world space; prim_id the segment index. On tubes
     v is the same formula at the tube's hit point, the signed offset
     across the fibre in [-1, 1] that hair BSDFs take (h in the
     Marschner and d'Eon models; its sign follows cross(P', X - P) along
     dir), equal at a circle's entry and exit.
     Attributes at a hit: hairobb_interpolate(bvh, hit.group_id,
     hit.prim_id, hit.u, ray time, p, d1, d2) gives the curve's point and
     radius and their first and second derivatives in u there (ray
     differentials, a shading frame); hairobb_basis_weights(basis, u, w,
     dw) the weights of the segment's control points, so that per-vertex
     data of the caller's (colours, texture coordinates) interpolates as
     the curve does: sum_k w[k] data[indices[prim] + k].
     (Embree's flat curves report v in [-1, 1] too, and the tangent as Ng.)
     Every hit with t in [tnear, tfar] counts, including the ribbon a
     secondary ray starts on. Trace secondary rays with
     hairobb_intersect1_from / hairobb_occluded1_from, giving the hit they
     leave: they start at org + hit.t * dir with tnear = 0 and skip the
     ribbon they start on, its segment and the segments joined to its ends,
     within 2 radii (Embree drops every hit with t <= 2 r / |dir|, other
     hairs included; here other hairs in contact still cast shadows). On
     round curves only the sheet a ray leaves through is skipped there (a
     ray along `from`'s outward Ng skips exits, one against it entries):
     a ray going into the fibre finds its far side.
     An any-hit filter (options.hit_filter) sees each hit before it is
     taken: transparent hair, shadow rays through opacity. Which candidate
     hits it is shown, and in what order, depends on the traversal's order
     (nearest first for intersect1, none for occluded1), which may differ
     between SIMD paths and versions; the hit a call returns does not. A
     filter that is a pure function of its hit gives the same answers on
     every path. Occluded calls use options.occluded_filter where it is
     set. A filter sees each crossing of the ray once: where two pieces of
     a segment, or two segments at a strand's joint, find the same
     crossing, the second is not shown again once a filter has ignored the
     first (a transmittance product stays right). A tube's entry and exit
     are two crossings, however near its silhouette: the filter is shown
     both, as stepping intersect1 past each hit finds both.
     Per-call filters: hairobb_intersect1_context / hairobb_occluded1_context
     take a hairobb_context, a filter and its user pointer for that call
     (a ray's medium, depth or transmittance), called after the BVH's own
     filter (if any) for each hit that filter takes; a hit counts where
     both take it. from may be NULL there.


   7. BUILD OPTIONS (hairobb_build_options; a zero-initialised struct = defaults)
   ----------------
     nodes                   HAIROBB_NODES_MIXED (default): AABB or OBB per node
                             by SAH; _AABB_ONLY and _OBB_ONLY for comparisons.
     obb_layout              HAIROBB_OBB_DEFAULT = _COMPRESSED_PER_CHILD: each
                             child box in its own hair space, a rotation in
                             signed bytes, the box in signed bytes times a
                             step per axis (208 bytes per 8-wide node, 128
                             4-wide); the few nodes near the root (AABB nodes,
                             OBB nodes over 256 references) keep floats.
                             _PER_CHILD: the paper's uncompressed node, an
                             affine map per child (464/240 bytes, then
                             96/48 bytes of the child frames' directions,
                             which hairobb_refit makes the frames from).
                             _SHARED_ROTATION: one float rotation per node
                             (304/176 bytes). _COMPRESSED: the paper's
                             compressed node, one byte rotation shared by the
                             children (160/96 bytes). The default's nodes take
                             less than half the bytes of _PER_CHILD's and trace
                             about as fast; one rotation shared by all
                             children bounds them more loosely and traces
                             slower (docs/design.md, docs/benchmarking.md).
     spatial_splits          HAIROBB_AUTO (= off), _ON, _OFF: also try split
                             planes that clip segments (world and hair space);
                             a clipped segment is referenced by the leaves of
                             both sides. Off by default: on real hair it wins
                             few splits and costs build time and memory.
     spatial_split_budget    extra references spatial splits may add, as a
                             fraction of the segment count: 0 = 0.25, at most 4.
     clustering              HAIROBB_AUTO (= off), _ON, _OFF: also try splitting
                             by similar orientation (two main directions).
                             Spatial splits and clustering stop being tried in
                             a subtree where they lost 3 splits in a row.
     max_leaf_size           segments per leaf at most, 0 = 4, at most 15.
     hair_space_candidates   rotations tried per split (main directions of
                             sampled segments), 0 = 2, at most 16. More
                             candidates build slower; the paper's 4 traced
                             no faster than 2.
     curve_pieces            linear pieces per segment in the intersector's
                             first test, 0 = 8, at most 16 (with the exact
                             precision it changes speed, not the hits).
     precision               HAIROBB_PRECISION_EXACT (default): roots refined to
                             the surface above. HAIROBB_PRECISION_PIECES: the
                             linear pieces alone, faster, less accurate.
     allocator_user          passed to HAIROBB_MALLOC/HAIROBB_FREE.
     progress, progress_user progress(progress_user, fraction) is called as the
                             build goes (fraction rising to exactly 1), on
                             the calling thread only, from the first
                             splits of the (serial) top of the tree on,
                             which take the first fifth of the fraction;
                             a nonzero return cancels:
                             HAIROBB_ERROR_CANCELLED.
     threads                 0 (default): one build thread per core; 1: the
                             calling thread only; at most 256 (THREADS).
     parallel_for, _user     a renderer's task system instead of the
                             library's threads (THREADS).
     basis, tangents         HAIROBB_BASIS_BEZIER (default) reads 4 control
                             points from indices[i]. _BSPLINE, _CATMULL_ROM
                             (4 points), _HERMITE (2 points, their
                             derivatives at the same indices of `tangents`)
                             and _LINEAR (2 points) follow Embree's curve
                             types of those names; the build converts each
                             segment exactly to Bezier form (a basis change:
                             the same cubic, the same u) where it reads one.
                             Radii a conversion takes below 0 are clamped to 0.
     bezier_copy             static hair, every basis: AUTO/ON (default)
                             copy each leaf reference's Bezier control
                             points (other bases converted) into the BVH's
                             memory, in the order its leaves read them, 64
                             bytes on one cache line each, plus 4 bytes a
                             segment (8 for other bases, whose indices are
                             kept for hairobb_refit): about 100 bytes a
                             segment in all, less than Embree's default
                             (docs/benchmarking.md#memory). A
                             leaf visit then reads the BVH's own lines,
                             not the caller's arrays in whatever order
                             and pages the caller has them: on large
                             scenes in a groom generator's order it
                             traces markedly faster than OFF
                             (docs/benchmarking.md#at-scale), which is
                             why AUTO means ON. OFF keeps each
                             leaf reference's vertex offset in leaf order
                             (4 bytes) and reads the caller's points
                             there, converting other bases each time:
                             about a third of the bytes, no more than
                             Embree's compact mode takes
                             (docs/benchmarking.md#memory): the mode for
                             hair that would not fit twice. Both give the same tree and
                             bit-identical hits. Moving hair reads the
                             caller's steps, through the offsets too.
     hit_filter, _user       hit_filter(user, ray, hit) for each hit found
                             in [tnear, tfar] (nearer than the best so far
                             for intersect1, any for occluded1), on the
                             tracing thread, before it is taken: 0 ignores
                             it. Each crossing is shown once (HITS). NULL
                             (default): every hit counts; an unset filter
                             costs next to nothing.
     occluded_filter, _user  the same for occluded calls; NULL (default):
                             they use hit_filter.
     simd                    HAIROBB_SIMD_AUTO (default): the widest path
                             the build has and the CPU runs (SIMD PATHS);
                             a path named forces it (comparisons, tests),
                             HAIROBB_ERROR_UNSUPPORTED where the build
                             lacks it or the CPU cannot run it. A build
                             has one baseline path (its compiler target's:
                             SSE2 in a default x86-64 build, NEON on
                             AArch64, NONE with HAIROBB_NO_SIMD) and, on
                             x86 with dispatch, AVX2: a default x86-64
                             build takes AUTO, SSE2 and AVX2; NONE, SSE41
                             and AVX only where they are its baseline
                             (HAIROBB_NO_SIMD, -msse4.1, -mavx). Plain C
                             answers as every path, bit for bit.
                             hairobb_get_simd(bvh) tells a BVH's path.
     verify_hair             hairobb_load only (SAVE AND LOAD): HAIROBB_AUTO
                             (default) and _ON compare the hair with the
                             saved hash, _OFF skips that pass.
     time_steps, time_vertices  motion blur (MOTION BLUR); 0: static hair.
     shape                   HAIROBB_SHAPE_RIBBON (default): flat ribbons
                             facing the ray; HAIROBB_SHAPE_ROUND: tubes
                             (THE SURFACE), for close-ups; every basis,
                             motion, refit, save and load; the BVH and its
                             memory are the ribbon's.
     end_caps                round curves: HAIROBB_ON closes free ends with
                             flat caps; AUTO (default) and OFF leave them
                             open. Ribbons ignore it.
     back_faces              round curves: HAIROBB_OFF culls hits facing
                             away from the ray; AUTO (default) and ON keep
                             both sheets. Ribbons ignore it.


   8. THREADS and BUILD MEMORY
   ---------------------------
     THREADS: every thread count builds the same tree. The top levels are
     built on the calling thread; the independent subtrees below them (about
     64, from the input size alone) go to the other threads as the top makes
     them, then to all of them. The first pass over every segment, and the
     last one that gathers the subtrees, run on all threads in parts.
     With options.parallel_for (works with HAIROBB_NO_THREADS too;
     `threads` is then unused) the subtrees go to
     parallel_for(user, count, run, context) as one call of run(context, i)
     each, once the top is built (it takes a count, so the subtrees cannot
     start while the top runs, as they do on the library's threads). The
     first and last passes call it too, before the top and after the
     subtrees. The same tree again. While they run, progress is not
     reported and a cancel waits for their end. A parallel_for that skips
     an index gives HAIROBB_ERROR_INVALID_ARGUMENT.

     BUILD MEMORY: beyond the BVH it returns, a build holds 28 bytes a
     segment while it runs (ids and world boxes; 36 a reference with
     spatial splits, whose budget adds spatial_split_budget references a
     segment), 24 bytes a reference of the subtree each thread builds, a
     copy of that subtree's points in Bezier form (72 bytes a reference),
     and the subtrees' nodes, which it holds twice at the end as it copies
     them into one block. So its peak beyond the BVH stays below the BVH's
     own size without bezier_copy; with the copy (the default), written once
     that memory is freed, the BVH it returns is the peak
     (docs/benchmarking.md#memory has the measured figures).


   9. REFIT
   --------
     hairobb_refit(bvh, new_vertices) moves a built BVH to new positions
     and radii of the same segments (same indices and vertex_count, on the
     build's threads or parallel_for): the topology, the leaves and every
     node's frame stay as built, and every child box is written again, by
     the builder's own code, from the control points of the segments below
     it (clipped parts of spatial splits keep their u ranges), so it is as
     tight as a build's in those frames, and a refit to the build's
     positions gives back the build's bytes. Bad vertices (as the build
     checks them) return an error before anything is written. The copy
     (bezier_copy) is written again from the new points, converted from
     other bases, which keep a copy of the caller's indices; the BVH keeps
     the new pointer (MEMORY LIFETIME). Hermite takes new tangents with
     hairobb_refit_tangents.
     A refit costs a fraction of a build (docs/benchmarking.md).
     The frames suit the pose they were chosen for: hairobb_get_stats
     gives the tree's SAH cost now (sah_cost) and as built
     (build_sah_cost); rebuild when their ratio passes a threshold of your
     choosing. The ratio tracks the speed a refitted tree loses against a
     fresh build.


  10. MOTION BLUR
  ---------------
     options.time_steps = T >= 2 and options.time_vertices (T pointers to
     arrays of vertex_count control points, the same indices) describe
     moving hair: step k is the hair at time k / (T - 1). The surface at a
     ray's time tau (hairobb_ray.time, in [0, 1]) is THE SURFACE of the
     segment whose control points (position and radius) are interpolated
     linearly, in float, between the two steps around tau. hairobb_build's
     `vertices` is then unused (may be NULL); the BVH keeps the T pointers
     (copied, 8 bytes each: the caller's array of them may go), and the
     arrays must stay alive as vertices do (MEMORY LIFETIME). Any basis but
     Hermite (its tangents would have to move too: INVALID_ARGUMENT);
     another basis moves as its points: they are interpolated, then
     converted, read where they are (bezier_copy does not apply to moving
     hair). One tree serves every time. The compressed layouts (the default
     and HAIROBB_OBB_COMPRESSED) store linear bounds: each child's boxes at
     times 0 and 1, fitted to hold it at every step, lerped to the ray's
     time (8-wide: 48 bytes more a node than the still compressed nodes,
     which moving hair uses near the root too, where static hair has float
     nodes). The float layouts bound each segment by the union of its boxes
     at every step, which is loose for fast motion. Motion that curves
     between many steps (a large rotation over T > 2) bounds looser than the
     same motion in one step: no time splits yet. T = 0 or 1 is a static BVH
     (time_vertices unused), built and traced exactly as without these
     fields; static BVHs ignore ray.time.
     Errors: time_vertices NULL or a NULL step: INVALID_ARGUMENT; NaN,
     Inf, huge or negative radius at any step: INVALID_GEOMETRY. A ray of
     a motion-blurred BVH whose time is outside [0, 1] or NaN misses
     (intersect and occluded return 0). hairobb_refit_motion refits with
     new arrays for every step; save and load keep T (the load takes
     options.time_steps and time_vertices, and the hash covers every step;
     another T is HAIROBB_ERROR_MISMATCH).


  11. SCENES (several hair groups, instances)
  ---------------------------------------------
     GROUPS IN ONE BVH: a groom's descriptions (base, flyaways, clumps,
     brows) share space, each with its own arrays, shader and mask.
     hairobb_build_groups(groups, group_count, options, &bvh) builds one
     tree over every group's segments, leaves mixing groups freely, so a
     ray walks one tree however many groups overlap (a scene of one BVH a
     group walks each BVH whose box it crosses: several times slower where
     groups share space). Each hairobb_group holds its arrays as
     hairobb_build takes them (options.basis for all; tangents and motion
     steps per group), a mask and a user pointer. Hits name the group
     (hit.group_id) and the segment in it (hit.prim_id); hairobb_build's
     BVHs are one group, 0. The ray's mask (context->mask, on BVH calls
     and scene calls) is tested against each group's: a group is traced
     where they share a bit, 0 in either meaning every bit. A mask that
     excludes no group costs a ray nothing per segment. Filters see
     group_id; a secondary ray skips the segment it leaves in its own
     group only, and strands never join across groups (joints, caps).
     The caller's arrays may go after the build: the BVH keeps what it
     needs (static Bezier hair with the copy, the default: its indices, 4
     bytes a segment more than one BVH; other bases, bezier_copy OFF and
     moving hair: its own concatenation of the groups' arrays, 16 bytes a
     point more; hairobb_memory_bytes counts it). hairobb_refit_group
     moves one group (its new points, the others' as traced, the tree
     refitted);
     hairobb_refit and hairobb_refit_motion refuse a multi-group BVH.
     hairobb_save takes one; hairobb_load_groups loads it over the same
     groups (SAVE AND LOAD). A multi-group BVH
     traces as one BVH over the groups' arrays concatenated in group order
     does, hit for hit (tests/test_groups.c).
     hairobb_get_group_stats gives each group's counts, its leaf
     references and its share of hairobb_memory_bytes (what is held for
     it alone, and the rest by its leaf references).
     MIXED SHAPES: a group's shape (hairobb_group.shape) is options.shape
     or its own, so fur as ribbons and close-up hair as tubes share one
     tree; options.end_caps and back_faces apply to its tubes, and pieces
     precision is refused where a group is round. Each segment is traced
     as its group's shape, exactly as a BVH of that shape alone would (a
     bit a segment marks the tubes: a ribbon BVH pays nothing for it, a
     round one a load a segment). The shapes are saved; a load takes them,
     and refuses (MISMATCH) a group that asks for another.
     INSTANCES: a groom is often placed more than once. hairobb_scene_build(instances, count,
     allocator_user, &scene) puts BVHs under one top level: each
     hairobb_instance names a BVH (several may share one; the scene does
     not own them), an affine object-to-world map (3 rows of 4 floats:
     rotation, scale, shear, translation; any invertible map), a mask and a
     user pointer. hairobb_scene_intersect1 / _occluded1(scene, context,
     from, ray, ...) trace the ray through every instance it reaches and
     return the nearest hit (or whether there is one): hit->instance_id
     names the instance (hairobb_scene_user gives back its pointer),
     prim_id the segment in its BVH; t is the ray's own parameter (the ray
     is mapped into each instance, so t, u and v are the same in both
     spaces), Ng and the tangent are in world space (the normal mapped by
     the inverse transposed, then made unit). Ties in t go to the lower
     instance id. A BVH's own calls set instance_id to HAIROBB_INVALID_ID.
     Masks: an instance is traced by a ray when its mask and the ray's
     (context->mask) share a bit; 0 in either means every bit, so zeroed
     structs trace everything.
     Hit filters: each BVH's own filter and the call's (context->filter)
     see the caller's ray and hits in world space with instance_id set.
     Secondary rays: `from` is a scene hit; the segment left is skipped in
     its own instance only, so a ray reaches the same strand placed
     elsewhere. `hit` may be `from`.
     Moving: hairobb_scene_update(scene, instances, count) takes new maps,
     masks, users or BVHs (refit or rebuilt ones), as many as wanted
     (instances added or removed: the ids are the new array's), and
     rebuilds the top level (a binary tree over the instances' world boxes,
     quick next to any BVH's refit). Refit a BVH, then update the scenes
     that place it: a scene keeps the boxes it was given. A bad instance
     (no BVH; a map not finite, singular or beyond 1e18) is
     INVALID_ARGUMENT, and an update then changes nothing. An instance's
     map is one for the whole frame (ray.time moves the hair of a moving
     BVH, not the instance). Under a map that does not keep angles (shear,
     unequal scales) a ribbon faces the ray in object space and a tube's
     circles become ellipses: the shape the map makes of them.
     Round-off: the ray is mapped in double and rounded once; against one
     BVH built over the same hair placed in world space, hits agree as
     one BVH's agree with the reference (tests/test_instances.c).


  12. .hair FILES
  ---------------
     hairobb_hair_load(path, allocator_user, &hair) (or hairobb_hair_read
     from memory) reads Cem Yuksel's format: the file's arrays (points with
     radius = thickness / 2, strand lengths, colours and transparency where
     present) and Bezier segments through the points (uniform Catmull-Rom),
     ready for hairobb_build(hair.vertices, hair.vertex_count, hair.indices,
     hair.segment_count, ...). Keep the hairobb_hair until hairobb_free of
     the BVH, then hairobb_hair_free. A file whose size, counts or flags
     disagree is HAIROBB_ERROR_INVALID_FILE; NaN, Inf or negative thickness
     HAIROBB_ERROR_INVALID_GEOMETRY.


  13. SAVE AND LOAD
  -----------------
         size_t size = hairobb_save_size(bvh);
         void *bytes = malloc(size);
         hairobb_save(bvh, bytes, size);                  // or hairobb_save_file(bvh, path)
         ...
         hairobb_load(bytes, size, vertices, vertex_count, indices, segment_count, &options, &loaded);
     A load takes the hair arrays the build took (and keeps pointers to
     them, as a built BVH does) and traces bit for bit as the saved BVH did,
     on the path options.simd picks. Of the options it reads basis,
     tangents, time_steps and time_vertices (they must describe the saved
     hair), simd, hit_filter(_user), occluded_filter(_user),
     allocator_user, verify_hair, bezier_copy, and threads and
     parallel_for(_user) for a later hairobb_refit (a loaded BVH refits as
     the saved one would); every other setting (layout, policy, precision, curve pieces, leaf
     size) is the saved BVH's, and bezier_copy is the load's own. The
     copy is not saved: the load writes it again from the caller's arrays
     (other bases converted with the build's code). A load is many times
     faster than a build.
     The format: a header (magic, format version, byte-order word, node
     width, the build's options, counts, a 64-bit hash of the Bezier
     segments traced), the node memory, the leaves' segment ids (and the u
     ranges of segments spatial splits clipped, 8 bytes each, where there
     are some) and a 64-bit checksum of all of it, in this host's byte
     order; a multi-group BVH's bytes add its groups' sizes (first segment
     and first vertex of each) before the checksum, and load with
     hairobb_load_groups over the same groups. hairobb_save writes format
     HAIROBB_SAVE_FORMAT_VERSION (3 since the groups, after 0.2.0; 2
     in 0.2.0); hairobb_load reads it and the older formats down to
     HAIROBB_SAVE_FORMAT_OLDEST (1: 0.1.x's, whose hash covered Bezier
     input's whole arrays, vertex_count points and the indices). It is for
     builds of this library with the same node width: a newer format
     version, HAIROBB_NODE_WIDTH or byte order is HAIROBB_ERROR_UNSUPPORTED.
     Other hair is HAIROBB_ERROR_MISMATCH: another segment count, vertex
     count or basis, or segments that differ from the hash (any bit of a
     segment's Bezier control points, for other bases of the converted
     curves, so tangents too; for moving hair any bit of every step's
     arrays). verify_hair = HAIROBB_OFF
     skips the hash (a pass over the arrays) for a renderer that knows its
     hair is the one saved; the arrays are still validated as
     hairobb_build validates them, and every segment id is checked against
     segment_count, so a BVH loaded over other hair traces safely, only
     wrongly. The loader trusts nothing else either: sizes and counts
     (overflow-safe), header fields, the checksum, then a walk of the whole
     tree: every reference of a node type the saved layout and policy
     build and inside the node memory, every node reached once (no
     cycles, sharing or overlap, no byte unreached), no deeper than the
     traversal stack holds, inner nodes of 2 to W children (empty lanes
     last), leaves of 1 to max_leaf_size segments taking the ids in tree
     order, each id below segment_count, every segment named by some
     leaf. Anything wrong is
     HAIROBB_ERROR_INVALID_FILE, with nothing allocated left behind. The
     floats of nodes are not checked: a NaN or infinite box only makes
     rays miss children or visit more of them (hits come from the
     segments, and the walk bounds what a traversal reads); the bounds
     hairobb_bounds reports must be finite.


  14. SIMD PATHS
  --------------
     The traversal and intersector exist in plain C, SSE2, SSE4.1, AVX and
     AVX2 versions, which give the same hits bit for bit (no FMA). The
     compiler's target picks one (-msse4.1, -mavx2, -march=..., MSVC's
     /arch:AVX2). Where that target lacks AVX2, gcc 5+ and clang 4+ on x86,
     and MSVC on x64, compile the kernels a second time for AVX2 (target
     pragmas; MSVC needs none; no flag needed), and hairobb_build picks
     them where the CPU and its operating system run AVX2: a plain `cc -O2`
     build then traces about as fast as one for the CPU, and much faster
     than its SSE2 path. For that the file includes itself by its name:
     keep it hairobb.h, or define HAIROBB_SELF. HAIROBB_NO_DISPATCH turns
     the second copy off. On AArch64 (gcc, clang; MSVC's ARM64 reviewed
     only) the NEON path runs, with no dispatch: NEON is always there;
     nodes are 4-wide there by default. There is no AVX-512 path, and
     other CPUs run plain C. The compiler-specific spellings (inlining,
     bit scans, CPU checks, prefetches) are in one block of >>platform,
     for gcc and clang, and for MSVC; MSVC's are reviewed against its
     documentation but not compiled here (the tests build with gcc,
     clang and mingw-w64).


  15. THREAD SAFETY
  -----------------
     hairobb_intersect1/hairobb_occluded1 (and the _from variants) only
     read the BVH: any number of threads may trace one BVH at once;
     hairobb_refit writes it (no tracing meanwhile). The same for scenes:
     tracing reads, hairobb_scene_update writes. There is no global
     state.


  16. ERRORS
  ----------
     hairobb_build, hairobb_load, the refits and the readers return a
     hairobb_result; hairobb_result_string names it. On failure nothing is
     left allocated, and a refit leaves the BVH as it was. Validation
     (INVALID_GEOMETRY, INDEX_OUT_OF_RANGE, TOO_LARGE) comes before any
     large allocation. The library never prints and never exits.
     INVALID_ARGUMENT from a build or a load whose pointers and counts are
     fine is an option out of range: hairobb_check_options(&options) names
     the first such field. Besides each field's own range (BUILD OPTIONS)
     it refuses: tangents given with a basis other than Hermite, or
     missing for Hermite ("tangents"); time_steps over 65,535 or with the
     Hermite basis ("time_steps"); a NULL time_vertices or step
     ("time_vertices"); round curves with the pieces precision
     ("precision").


  17. SECTIONS OF THIS FILE
  -------------------------
     The implementation follows the data's path. Grep for these anchors
     (docs/design.md walks through them):
       >>api             the declarations below this manual
       >>implementation  what HAIROBB_IMPLEMENTATION compiles:
       >>platform        the C library, allocation, instruction sets, threads, spellings, huge pages
       >>defaults        limits, named default constants, the SAH cost model, node references
       >>vector          small vector helpers
       >>bvh             the BVH object: what a build or a load fills in
       >>input           results, options resolved once, validation, curve bases, segment bounds
       >>hair_file       the .hair reader
       >>hair_space      references, the builder's state, frames and the choice of a hair space
       >>bins            binned SAH: object and spatial bins, world and hair space, in parts
       >>splits          clustering, node boxes, the cheapest split
       >>partition       references to their side of a split, clipping
       >>node_store      node memory, progress, leaves
       >>layouts         each node layout's struct and writer
       >>node_build      a node of W children, a range to a subtree
       >>tasks           subtrees on threads or on parallel_for
       >>passes          the passes over every segment, and the build's steps
       >>build_api       hairobb_build, hairobb_free, memory and stats
       >>refit           refit and the SAH cost
       >>groups          several hair groups in one BVH: hairobb_build_groups
       >>save_load       the saved format and the loader's checks
       >>rays            what every traversal path reads of a ray
       >>kernels         compiled once, and again for AVX2 where dispatched:
       >>simd            SIMD wrappers and their plain C twins
       >>segment_points  a segment's Bezier points as traced
       >>intersector     what ribbons and tubes share: ray space, the power form
       >>hit             hit attributes, filters, the nearest hit so far
       >>ribbon          ribbons: the pieces, their roots, the polish
       >>tube            tubes: inside intervals and both sheets' roots
       >>segment         a segment's cull and a leaf's segments
       >>traversal       each layout's node test and the traversal loop
       >>tracing_api     hairobb_intersect1 and its siblings
       >>scene           instances under a top level: hairobb_scene_*
       >>dispatch        the kernels' names for their AVX2 copy
       >>licence         the licence, at the end
*/
#ifndef HAIROBB_H
#define HAIROBB_H
/* ------------------------------------------------------------------------ */
/* >>api  The API: types and functions (the manual above)                   */
/* ------------------------------------------------------------------------ */

#include <stddef.h>
#include <stdint.h>

#define HAIROBB_VERSION_MAJOR 0
#define HAIROBB_VERSION_MINOR 2
#define HAIROBB_VERSION_PATCH 0
#define HAIROBB_VERSION (HAIROBB_VERSION_MAJOR * 10000 + HAIROBB_VERSION_MINOR * 100 + HAIROBB_VERSION_PATCH)
/* The format hairobb_save writes (SAVE AND LOAD); hairobb_load reads it
   and every format from HAIROBB_SAVE_FORMAT_OLDEST on. */
#define HAIROBB_SAVE_FORMAT_VERSION 3
#define HAIROBB_SAVE_FORMAT_OLDEST 1

#if defined(HAIROBB_STATIC) && (defined(__GNUC__) || defined(__clang__))
#define HAIROBB_DEF static __attribute__((unused)) /* a file need not call every function */
#elif defined(HAIROBB_STATIC)
#define HAIROBB_DEF static
#else
#define HAIROBB_DEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum hairobb_result {
    HAIROBB_OK = 0,
    HAIROBB_ERROR_INVALID_ARGUMENT,   /* NULL pointer, zero segments, bad option value */
    HAIROBB_ERROR_INDEX_OUT_OF_RANGE, /* indices[i] + 3 >= vertex_count (+ 1 for Hermite and linear) */
    HAIROBB_ERROR_INVALID_GEOMETRY,   /* NaN/Inf, |coordinate| or radius > 1e18, negative radius */
    HAIROBB_ERROR_OUT_OF_MEMORY,      /* HAIROBB_MALLOC returned NULL */
    HAIROBB_ERROR_TOO_LARGE,          /* counts whose byte sizes overflow, > 2^32-1 segments */
    HAIROBB_ERROR_CANCELLED,          /* the progress callback asked to stop */
    HAIROBB_ERROR_INVALID_FILE,       /* .hair data: bad magic, reserved flags, counts that disagree with the size;
                                         a saved BVH: anything wrong (SAVE AND LOAD) */
    HAIROBB_ERROR_IO,                 /* a file could not be opened, read or written */
    HAIROBB_ERROR_UNSUPPORTED,        /* options.simd: a path this build or this CPU lacks; a saved BVH of
                                         another format version, node width or byte order */
    HAIROBB_ERROR_MISMATCH            /* hairobb_load: the BVH was saved over other hair (or another basis) */
} hairobb_result;

HAIROBB_DEF const char *hairobb_result_string(hairobb_result r);

typedef enum hairobb_node_policy {
    HAIROBB_NODES_MIXED = 0,
    HAIROBB_NODES_AABB_ONLY,
    HAIROBB_NODES_OBB_ONLY
} hairobb_node_policy;

typedef enum hairobb_precision {
    HAIROBB_PRECISION_EXACT = 0,  /* roots of dot(P2,P2') refined: the surface as defined */
    HAIROBB_PRECISION_PIECES      /* linear pieces only (like Embree's flat curves) */
} hairobb_precision;

/* The surface a segment is (THE SURFACE). */
typedef enum hairobb_shape {
    HAIROBB_SHAPE_RIBBON = 0,     /* a flat ribbon facing the ray (Embree's flat curves) */
    HAIROBB_SHAPE_ROUND           /* a tube: a swept circle (Embree's round curves), both sheets */
} hairobb_shape;

/* How an OBB node stores its child boxes (sizes for 4-/8-wide nodes). */
typedef enum hairobb_obb_layout {
    HAIROBB_OBB_DEFAULT = 0,         /* the layout the bench recommends (see BUILD OPTIONS) */
    HAIROBB_OBB_PER_CHILD,           /* an affine map per child (the paper's uncompressed node): 240/464 bytes + 48/96 */
    HAIROBB_OBB_SHARED_ROTATION,     /* one float rotation per node, float boxes in it: 176/304 bytes */
    HAIROBB_OBB_COMPRESSED,          /* the paper's: one byte rotation, byte boxes (AABB nodes too): 96/160 bytes */
    HAIROBB_OBB_COMPRESSED_PER_CHILD /* a byte rotation per child, byte boxes (AABB nodes as above): 128/208 bytes */
} hairobb_obb_layout;

/* A heuristic left to the library's recommendation, forced on, or off. */
typedef enum hairobb_switch {
    HAIROBB_AUTO = 0,
    HAIROBB_ON,
    HAIROBB_OFF
} hairobb_switch;

/* Called during a build with the fraction done (0..1, increasing);
   returning nonzero cancels the build (HAIROBB_ERROR_CANCELLED). */
typedef int (*hairobb_progress_fn)(void *user, float fraction);

/* How the control points of segment i are read, from vertex indices[i] on
   (Embree's conventions for its curve types of the same names). */
typedef enum hairobb_basis {
    HAIROBB_BASIS_BEZIER = 0,   /* 4 points: the cubic Bezier (default) */
    HAIROBB_BASIS_BSPLINE,      /* 4 points: the uniform cubic B-spline segment */
    HAIROBB_BASIS_CATMULL_ROM,  /* 4 points: the uniform Catmull-Rom segment from the 2nd to the 3rd */
    HAIROBB_BASIS_HERMITE,      /* 2 points and their derivatives (options.tangents) */
    HAIROBB_BASIS_LINEAR        /* 2 points: a straight segment */
} hairobb_basis;

/* The instruction set a BVH's traversal and intersector use. Every path
   gives the same answers, bit for bit. */
typedef enum hairobb_simd {
    HAIROBB_SIMD_AUTO = 0,      /* options.simd: the widest path this build and this CPU run (default) */
    HAIROBB_SIMD_NONE,          /* plain C */
    HAIROBB_SIMD_SSE2,
    HAIROBB_SIMD_SSE41,
    HAIROBB_SIMD_AVX,
    HAIROBB_SIMD_AVX2,
    HAIROBB_SIMD_NEON           /* AArch64, where NEON is always present */
} hairobb_simd;

/* A renderer's own task system for the build (options.parallel_for): it
   calls run(context, i) once for each i in [0, count), on any threads and
   in any order, and returns when every call has returned. */
typedef void (*hairobb_task_fn)(void *context, unsigned index);
typedef void (*hairobb_parallel_for_fn)(void *user, unsigned count, hairobb_task_fn run, void *context);

struct hairobb_ray;
struct hairobb_hit;
/* An any-hit filter: called for each hit a ray finds before it is taken
   (transparent hair, shadow rays through opacity); nonzero takes it, 0
   ignores it and the ray goes on. ray is the caller's (a renderer can keep
   its own data around it). */
typedef int (*hairobb_filter_fn)(void *user, const struct hairobb_ray *ray, const struct hairobb_hit *hit);

typedef struct hairobb_build_options {
    hairobb_node_policy nodes;
    hairobb_obb_layout obb_layout;
    unsigned max_leaf_size;          /* 0 = 4; 1..15 */
    unsigned hair_space_candidates;  /* 0 = 2; 1..16 */
    unsigned curve_pieces;           /* 0 = 8; 1..16 */
    hairobb_precision precision;
    void *allocator_user;
    hairobb_switch spatial_splits;   /* clip segments at split planes */
    float spatial_split_budget;      /* extra segment references allowed, a fraction of the
                                        segment count; 0 = 0.25; at most 4 */
    hairobb_switch clustering;       /* similar-orientation clustering */
    hairobb_progress_fn progress;    /* NULL: none; called on the calling thread only */
    void *progress_user;
    unsigned threads;                /* 0 = one per core; 1 = the calling thread only; at most 256 */
    hairobb_basis basis;             /* how vertices and indices describe segments */
    const float *tangents;           /* HAIROBB_BASIS_HERMITE: 4 floats per vertex, dP/du and dr/du */
    hairobb_filter_fn hit_filter;    /* NULL: every hit counts */
    void *hit_filter_user;
    hairobb_simd simd;               /* HAIROBB_SIMD_AUTO, or a path to force */
    hairobb_parallel_for_fn parallel_for; /* NULL: the library's threads (see `threads`) */
    void *parallel_for_user;
    hairobb_switch verify_hair;      /* hairobb_load: AUTO/ON compare the hair with the saved hash, OFF skip it */
    hairobb_switch bezier_copy;      /* static hair: AUTO/ON trace a copy in leaf order, OFF the caller's arrays */
    /* Motion blur (MOTION BLUR): time_steps >= 2 arrays of vertex_count control
       points each, the hair at times k / (time_steps - 1); 0 or 1: static */
    unsigned time_steps;
    const float *const *time_vertices;
    hairobb_shape shape;             /* HAIROBB_SHAPE_RIBBON (0) or _ROUND (THE SURFACE) */
    hairobb_switch end_caps;         /* round curves: ON closes each free end with a flat cap; AUTO/OFF open (THE SURFACE) */
    hairobb_switch back_faces;       /* round curves: AUTO/ON both sheets, OFF only where rays enter (THE SURFACE) */
    hairobb_filter_fn occluded_filter;  /* occluded calls' filter; NULL: they use hit_filter */
    void *occluded_filter_user;
} hairobb_build_options;

typedef struct hairobb_bvh hairobb_bvh;

/* All defaults (every field zero): hairobb_build_options o =
   hairobb_default_options(); reads the same in C and C++ (where = {0}
   does not compile: the first field is an enum; = {} does). */
HAIROBB_DEF hairobb_build_options hairobb_default_options(void);
/* NULL where every field is in range; else the name of the first field
   that is not ("max_leaf_size", "tangents", ...), which hairobb_build
   refuses with INVALID_ARGUMENT. */
HAIROBB_DEF const char *hairobb_check_options(const hairobb_build_options *options);

/* Builds a BVH over segment_count segments. options may be NULL (defaults).
   The BVH keeps pointers to vertices and indices (see MEMORY LIFETIME).
   On failure *out is NULL and nothing is leaked. */
HAIROBB_DEF hairobb_result hairobb_build(const float *vertices, size_t vertex_count,
                                         const uint32_t *indices, size_t segment_count,
                                         const hairobb_build_options *options, hairobb_bvh **out);
HAIROBB_DEF void hairobb_free(hairobb_bvh *bvh);

/* Several hair groups in one BVH (GROUPS): a groom's descriptions (base,
   flyaways, brows...) as one tree, hits naming the group (hit.group_id)
   and the segment in it (hit.prim_id). Each group's arrays are as
   hairobb_build takes them, in options.basis. */
/* A group's surface: options.shape, or its own, so that fur as ribbons
   and close-up hair as tubes share one tree (MIXED SHAPES in SCENES). */
typedef enum hairobb_group_shape {
    HAIROBB_GROUP_SHAPE_OPTIONS = 0,   /* options.shape */
    HAIROBB_GROUP_SHAPE_RIBBON,        /* HAIROBB_SHAPE_RIBBON whatever options.shape says */
    HAIROBB_GROUP_SHAPE_ROUND          /* HAIROBB_SHAPE_ROUND whatever options.shape says */
} hairobb_group_shape;
typedef struct hairobb_group {
    const float *vertices;      /* vertex_count x (x, y, z, radius); NULL for moving hair (time_vertices) */
    size_t vertex_count;
    const uint32_t *indices;    /* segment_count first control points, into this group's vertices */
    size_t segment_count;
    const float *tangents;      /* HAIROBB_BASIS_HERMITE: 4 floats per vertex; else NULL */
    const float *const *time_vertices;  /* motion blur: options.time_steps arrays of vertex_count points; else NULL */
    uint32_t mask;              /* traced by rays whose mask (hairobb_context.mask) shares a bit; 0 = every bit */
    void *user;                 /* given back by hairobb_group_user */
    hairobb_group_shape shape;  /* HAIROBB_GROUP_SHAPE_OPTIONS (0): options.shape; or this group's own */
} hairobb_group;
/* One BVH over every segment of group_count groups (options for all of
   them; options.tangents and options.time_vertices are ignored: each
   group's are its own). The BVH keeps its own copy of the groups' arrays:
   the caller's may go after the build. A group with no segments is
   allowed (it is never hit); group_count 0 or no segments at all is
   INVALID_ARGUMENT, a group's bad index INDEX_OUT_OF_RANGE, bad points
   INVALID_GEOMETRY. */
HAIROBB_DEF hairobb_result hairobb_build_groups(const hairobb_group *groups, size_t group_count,
                                                const hairobb_build_options *options, hairobb_bvh **out);
/* New positions (and tangents, Hermite) of one group: vertex_count points
   as built, copied in; the tree is refitted (REFIT). Moving BVHs: time_vertices
   of the group's steps (vertices NULL). Errors as hairobb_refit's; the BVH
   is left as it was. */
HAIROBB_DEF hairobb_result hairobb_refit_group(hairobb_bvh *bvh, uint32_t group_id, const float *vertices, const float *tangents,
                                               const float *const *time_vertices);
/* The group count (1 for hairobb_build's BVHs), a group's user pointer
   and its segment count (0 for a group id out of range). */
HAIROBB_DEF uint32_t hairobb_group_count(const hairobb_bvh *bvh);
HAIROBB_DEF void *hairobb_group_user(const hairobb_bvh *bvh, uint32_t group_id);
HAIROBB_DEF size_t hairobb_group_segments(const hairobb_bvh *bvh, uint32_t group_id);
/* What each group holds and costs (hairobb_get_group_stats). */
typedef struct hairobb_group_stats {
    size_t segment_count, vertex_count;
    size_t leaf_references;   /* its segments' entries in leaves (a spatial split lists a segment in several) */
    size_t bytes;             /* its share of hairobb_memory_bytes: what the BVH holds for it alone (its points,
                                 tangents, indices) and the rest in proportion to its leaf references; the groups'
                                 shares add up to hairobb_memory_bytes */
    hairobb_shape shape;      /* its segments' surface */
} hairobb_group_stats;
/* stats[g] for each group g below count and hairobb_group_count; returns
   how many it wrote (0 for NULL). One pass over the leaves. */
HAIROBB_DEF uint32_t hairobb_get_group_stats(const hairobb_bvh *bvh, hairobb_group_stats *stats, uint32_t count);

/* Refit (see REFIT): the same segments at new positions (and radii),
   vertices as the build's (the same vertex_count and indices). The tree
   keeps its topology and frames; every box is recomputed, and the copy
   (bezier_copy) written again. The BVH keeps the new pointer, which it
   reads as MEMORY LIFETIME says. NULL: INVALID_ARGUMENT;
   NaN/Inf, |coordinate| or radius > 1e18 or a negative radius:
   INVALID_GEOMETRY, and the BVH is left as it was. Hermite BVHs need new tangents too:
   hairobb_refit_tangents (tangents NULL for every other basis). Not while
   another thread traces the BVH. */
HAIROBB_DEF hairobb_result hairobb_refit(hairobb_bvh *bvh, const float *vertices);
HAIROBB_DEF hairobb_result hairobb_refit_tangents(hairobb_bvh *bvh, const float *vertices, const float *tangents);
/* Refit of a motion-blurred BVH (MOTION BLUR): new arrays for each of its
   time_steps (time_vertices[k], vertex_count control points each; the BVH
   keeps these pointers, not the array of them). A static BVH, a NULL
   array or step: INVALID_ARGUMENT; bad vertices at any step:
   INVALID_GEOMETRY, the BVH left as it was. hairobb_refit of a
   motion-blurred BVH is INVALID_ARGUMENT. */
HAIROBB_DEF hairobb_result hairobb_refit_motion(hairobb_bvh *bvh, const float *const *time_vertices);

/* Every byte the BVH allocated (the caller's arrays are not counted). */
HAIROBB_DEF size_t hairobb_memory_bytes(const hairobb_bvh *bvh);

typedef struct hairobb_stats {
    size_t aabb_nodes, obb_nodes, leaves;    /* obb_nodes: either layout */
    size_t leaf_references;   /* segment references in leaves */
    unsigned max_depth;       /* root = 0 */
    size_t node_bytes, leaf_bytes;
    /* SAH cost of the tree (see REFIT), now and as built (equal until a
       refit): a renderer that refits can rebuild when sah_cost /
       build_sah_cost passes a threshold. Computed by hairobb_get_stats from
       the stored boxes (a walk over the nodes, cheap next to a build). */
    double sah_cost, build_sah_cost;
} hairobb_stats;
HAIROBB_DEF void hairobb_get_stats(const hairobb_bvh *bvh, hairobb_stats *stats);

/* The path the BVH traces with (HAIROBB_SIMD_NONE for NULL), and its name. */
HAIROBB_DEF hairobb_simd hairobb_get_simd(const hairobb_bvh *bvh);
HAIROBB_DEF const char *hairobb_simd_string(hairobb_simd simd);

/* Bounds of all ribbons, radius included. */
HAIROBB_DEF void hairobb_bounds(const hairobb_bvh *bvh, float lower[3], float upper[3]);
/* The curve at a hit (rtcInterpolate's job, HITS): position and radius
   (x, y, z, r) and their first and second derivatives in u, of segment
   prim_id of group group_id (0 for hairobb_build's BVHs) at u, at `time`
   for moving hair (else ignored), as traced. Any of p, d1, d2 may be NULL;
   0 for ids out of range or a time outside [0, 1] of moving hair. */
HAIROBB_DEF int hairobb_interpolate(const hairobb_bvh *bvh, uint32_t group_id, uint32_t prim_id, float u, float time, float p[4],
                                    float d1[4], float d2[4]);
/* The weights at u of a segment's control points in basis, and of their
   derivatives (dw may be NULL): the caller's own per-vertex data a
   (colour, a texture coordinate) at a hit is sum_k w[k] a[i + k], i the
   segment's index (indices[prim_id] of its group), k < 4 (Bezier,
   B-spline, Catmull-Rom) or 2 (linear: w[2] = w[3] = 0). Hermite: w[0],
   w[1] weigh the two points, w[2], w[3] their tangents. */
HAIROBB_DEF void hairobb_basis_weights(hairobb_basis basis, float u, float w[4], float dw[4]);

/* Saving and loading a built BVH (SAVE AND LOAD in the manual).
   hairobb_save_size: the bytes hairobb_save writes (0 for NULL).
   hairobb_save: writes them into buffer; HAIROBB_ERROR_INVALID_ARGUMENT
   (nothing written) if size is smaller or a pointer NULL. A multi-group
   BVH's bytes hold its groups' sizes; they load with hairobb_load_groups. */
HAIROBB_DEF size_t hairobb_save_size(const hairobb_bvh *bvh);
HAIROBB_DEF hairobb_result hairobb_save(const hairobb_bvh *bvh, void *buffer, size_t size);
/* A BVH from the size bytes hairobb_save wrote (nothing of buffer is kept),
   over the same hair it was built on: the caller's arrays as hairobb_build
   takes them (the BVH keeps pointers to them, see MEMORY LIFETIME) and
   options (may be NULL) for basis, tangents, time_steps, time_vertices,
   simd, hit_filter, occluded_filter (and their user pointers),
   allocator_user, verify_hair, bezier_copy, threads and parallel_for;
   every other option is the saved BVH's (a BVH saved with or without the copy loads either way).
   It traces as the saved BVH did, bit for bit. On failure *out is NULL and
   nothing is leaked: HAIROBB_ERROR_INVALID_FILE (anything wrong in the
   bytes), _UNSUPPORTED (saved by another format version, node width or
   byte order), _MISMATCH (other hair, segment count or basis), the errors
   of hairobb_build's validation of the arrays, _OUT_OF_MEMORY. */
HAIROBB_DEF hairobb_result hairobb_load(const void *buffer, size_t size,
                                        const float *vertices, size_t vertex_count,
                                        const uint32_t *indices, size_t segment_count,
                                        const hairobb_build_options *options, hairobb_bvh **out);
/* A multi-group BVH from the bytes hairobb_save wrote, over the same
   groups (hairobb_build_groups' arguments; masks and users may be new).
   Groups of other sizes: HAIROBB_ERROR_MISMATCH, as is a multi-group BVH's
   bytes given to hairobb_load; a one-group BVH's bytes load here as one
   group. Otherwise as hairobb_load. */
HAIROBB_DEF hairobb_result hairobb_load_groups(const void *buffer, size_t size, const hairobb_group *groups, size_t group_count,
                                               const hairobb_build_options *options, hairobb_bvh **out);
#ifndef HAIROBB_NO_STDIO
/* The same through a file (HAIROBB_ERROR_IO if it cannot be opened, read or
   written); each holds the whole file in memory once while it runs. */
HAIROBB_DEF hairobb_result hairobb_save_file(const hairobb_bvh *bvh, const char *path);
HAIROBB_DEF hairobb_result hairobb_load_file(const char *path,
                                             const float *vertices, size_t vertex_count,
                                             const uint32_t *indices, size_t segment_count,
                                             const hairobb_build_options *options, hairobb_bvh **out);
#endif

typedef struct hairobb_ray {
    float org[3]; float tnear;
    float dir[3]; float tfar;   /* dir need not be normalised; t is in units of |dir| */
    float time;                 /* in [0, 1], read by motion-blurred BVHs only (MOTION BLUR) */
} hairobb_ray;

#define HAIROBB_INVALID_ID 0xffffffffu

typedef struct hairobb_hit {
    float t, u, v;      /* distance, curve parameter, signed position across the ribbon */
    float Ng[3];        /* unit geometric normal: the ribbon's, facing the ray origin; a tube's, outward */
    float tangent[3];   /* dP/du at u in world space, not normalised */
    uint32_t prim_id;   /* segment index, HAIROBB_INVALID_ID on a miss */
    uint32_t instance_id;   /* scenes (SCENES): the instance hit; HAIROBB_INVALID_ID from a BVH's own calls and on a miss */
    uint32_t group_id;      /* the group of prim_id (GROUPS); 0 in hairobb_build's BVHs; HAIROBB_INVALID_ID on a miss */
} hairobb_hit;

/* 1: nearest hit in [tnear, tfar] written to *hit; 0: miss, hit->prim_id and instance_id = HAIROBB_INVALID_ID. */
HAIROBB_DEF int hairobb_intersect1(const hairobb_bvh *bvh, const hairobb_ray *ray, hairobb_hit *hit);
/* 1: some segment is hit in [tnear, tfar]; stops at the first one found. */
HAIROBB_DEF int hairobb_occluded1(const hairobb_bvh *bvh, const hairobb_ray *ray);

/* Secondary rays (shadow, bounce) leaving the hit `from` of an earlier ray:
   start them at its hit point, org + from->t * dir of that ray, with
   tnear = 0. Hits on the segment left (from->prim_id) and on the segments
   joined to its ends (first or last control point at the same position)
   closer than 2 * its largest radius / |dir|, plus the rounding of org,
   are ignored: the ribbon the ray starts on, whatever way it faces the new
   ray. Every other segment counts from tnear on, however close (contact
   shadows between hairs stay). from == NULL: the plain functions above.
   `hit` may point to the same hit as `from` (a path tracer's loop). */
HAIROBB_DEF int hairobb_intersect1_from(const hairobb_bvh *bvh, const hairobb_hit *from, const hairobb_ray *ray,
                                        hairobb_hit *hit);
HAIROBB_DEF int hairobb_occluded1_from(const hairobb_bvh *bvh, const hairobb_hit *from, const hairobb_ray *ray);

/* A per-call hit filter (HITS): filter(user, ray, hit) for each hit the
   BVH's own filter takes, on the calling thread; 0 ignores the hit. */
typedef struct hairobb_context {
    hairobb_filter_fn filter;   /* NULL: none for this call */
    void *user;
    uint32_t mask;              /* the ray's mask against instances' (SCENES) and groups' (GROUPS); 0 = every bit */
} hairobb_context;

/* intersect1 / occluded1 with a per-call filter; context and from may be
   NULL (then these are hairobb_intersect1_from / hairobb_occluded1_from). */
HAIROBB_DEF int hairobb_intersect1_context(const hairobb_bvh *bvh, const hairobb_context *context, const hairobb_hit *from,
                                           const hairobb_ray *ray, hairobb_hit *hit);
HAIROBB_DEF int hairobb_occluded1_context(const hairobb_bvh *bvh, const hairobb_context *context, const hairobb_hit *from,
                                          const hairobb_ray *ray);

/* Several hair groups in one scene (SCENES): instances of BVHs, each with
   an affine map, a mask and a user pointer, under one top level. */
typedef struct hairobb_scene hairobb_scene;
typedef struct hairobb_instance {
    const hairobb_bvh *bvh;   /* the hair it places (not owned; several instances may share one) */
    float transform[12];      /* object to world, 3 rows of 4: world_i = m[4i] x + m[4i+1] y + m[4i+2] z + m[4i+3] */
    uint32_t mask;            /* traced by rays whose mask shares a bit with it; 0 = every bit */
    void *user;               /* given back by hairobb_scene_user */
} hairobb_instance;

HAIROBB_DEF hairobb_result hairobb_scene_build(const hairobb_instance *instances, size_t count, void *allocator_user,
                                               hairobb_scene **out);
/* new instances: maps, masks, users or BVHs (refit or rebuilt), and as
   many as wanted (instances added or removed; ids are the new array's) */
HAIROBB_DEF hairobb_result hairobb_scene_update(hairobb_scene *scene, const hairobb_instance *instances, size_t count);
HAIROBB_DEF void hairobb_scene_free(hairobb_scene *scene);
HAIROBB_DEF void *hairobb_scene_user(const hairobb_scene *scene, uint32_t instance_id);
/* The instance count; the world bounds of every instance's box (lower >
   upper for no instance); the bytes the scene allocated (not its BVHs'). */
HAIROBB_DEF size_t hairobb_scene_count(const hairobb_scene *scene);
HAIROBB_DEF void hairobb_scene_bounds(const hairobb_scene *scene, float lower[3], float upper[3]);
HAIROBB_DEF size_t hairobb_scene_memory_bytes(const hairobb_scene *scene);
/* as hairobb_intersect1_context / hairobb_occluded1_context over every
   instance; hit->instance_id says which (context, from may be NULL) */
HAIROBB_DEF int hairobb_scene_intersect1(const hairobb_scene *scene, const hairobb_context *context, const hairobb_hit *from,
                                         const hairobb_ray *ray, hairobb_hit *hit);
HAIROBB_DEF int hairobb_scene_occluded1(const hairobb_scene *scene, const hairobb_context *context, const hairobb_hit *from,
                                        const hairobb_ray *ray);

/* Cem Yuksel's .hair files (www.cemyuksel.com/research/hairmodels): the
   file's arrays, and Bezier segments made from them, ready for hairobb_build. */
typedef struct hairobb_hair {
    /* segments: a uniform Catmull-Rom spline through each strand's points
       (end points repeated), in Bezier form; consecutive segments of a strand
       share their end control point */
    float *vertices;           /* vertex_count x (x, y, z, radius), 16-byte aligned, then 16
                                  bytes of zeros (Embree reads past the last vertex) */
    size_t vertex_count;
    uint32_t *indices;         /* segment_count first control points */
    size_t segment_count;
    uint32_t *segment_point;   /* segment i runs from point segment_point[i] (u = 0) to the next (u = 1) */
    /* the file */
    uint32_t strand_count, point_count;
    uint32_t *strand_points;   /* points of each strand (its segments + 1) */
    float *points;             /* point_count x (x, y, z, radius), radius = thickness / 2 */
    float *transparency;       /* point_count values, or NULL: default_transparency everywhere */
    float *colors;             /* point_count x (r, g, b), or NULL: default_color everywhere */
    float default_transparency, default_color[3];
    char info[89];             /* the header's text, NUL-terminated */
    void *allocator_user;
    void *allocation;          /* the one block holding every array above */
} hairobb_hair;

/* Reads .hair data from memory (size bytes; nothing of data is kept). The
   size must be exactly what the header announces. On failure *hair is
   zeroed and nothing is leaked. allocator_user is passed to HAIROBB_MALLOC. */
HAIROBB_DEF hairobb_result hairobb_hair_read(const void *data, size_t size, void *allocator_user, hairobb_hair *hair);
#ifndef HAIROBB_NO_STDIO
/* The same from a file (HAIROBB_ERROR_IO if it cannot be opened or read). */
HAIROBB_DEF hairobb_result hairobb_hair_load(const char *path, void *allocator_user, hairobb_hair *hair);
#endif
/* Frees what hairobb_hair_read/hairobb_hair_load allocated; NULL is ignored. */
HAIROBB_DEF void hairobb_hair_free(hairobb_hair *hair);

#ifdef __cplusplus
}
#endif
#endif /* HAIROBB_H */

/* ======================================================================== */
/* >>implementation                                                         */
/* ======================================================================== */
#ifdef HAIROBB_IMPLEMENTATION
/* HAIROBB__KERNEL_PASS: the file includes itself to compile the kernels again */
#if !defined(HAIROBB_IMPLEMENTATION_DONE) || defined(HAIROBB__KERNEL_PASS)
#ifndef HAIROBB__KERNEL_PASS
#define HAIROBB_IMPLEMENTATION_DONE

/* ------------------------------------------------------------------------ */
/* >>platform  Platform: C library, allocation, instruction sets, threads   */
/* ------------------------------------------------------------------------ */
#include <float.h>
#include <math.h>
#include <string.h>
#ifndef HAIROBB_NO_STDIO
#include <stdio.h>
#endif

#if defined(HAIROBB_MALLOC) != defined(HAIROBB_FREE)
#error "define both HAIROBB_MALLOC and HAIROBB_FREE, or neither"
#endif
#ifndef HAIROBB_MALLOC
#include <stdlib.h>
#define HAIROBB_MALLOC(size, user) ((void)(user), malloc(size))
#define HAIROBB_FREE(ptr, user) ((void)(user), free(ptr))
#endif
#ifndef HAIROBB_ASSERT
#include <assert.h>
#define HAIROBB_ASSERT(x) assert(x)
#endif

/* The instruction sets the compiler targets: the kernels' baseline path. */
#define HAIROBB__SSE 0
#define HAIROBB__SSE41 0
#define HAIROBB__AVX 0
#define HAIROBB__AVX2 0
#if !defined(HAIROBB_NO_SIMD) && (defined(__SSE2__) || defined(_M_X64))
#undef HAIROBB__SSE
#define HAIROBB__SSE 1
#include <emmintrin.h>
#if defined(__SSE4_1__)
#undef HAIROBB__SSE41
#define HAIROBB__SSE41 1
#include <smmintrin.h>
#endif
#if defined(__AVX__)
#undef HAIROBB__AVX
#define HAIROBB__AVX 1
#include <immintrin.h>
#endif
#if defined(__AVX2__)
#undef HAIROBB__AVX2
#define HAIROBB__AVX2 1
#endif
#endif
/* AArch64 always has NEON (Advanced SIMD): its path needs no dispatch. */
#define HAIROBB__NEON 0
#if !defined(HAIROBB_NO_SIMD) && (defined(__aarch64__) || defined(_M_ARM64)) && !HAIROBB__SSE
#undef HAIROBB__NEON
#define HAIROBB__NEON 1
#include <arm_neon.h>
#endif
#define HAIROBB__BASELINE_SIMD (HAIROBB__AVX2 ? HAIROBB_SIMD_AVX2 : HAIROBB__AVX ? HAIROBB_SIMD_AVX : \
                                HAIROBB__SSE41 ? HAIROBB_SIMD_SSE41 : HAIROBB__SSE ? HAIROBB_SIMD_SSE2 : \
                                HAIROBB__NEON ? HAIROBB_SIMD_NEON : HAIROBB_SIMD_NONE)
/* Runtime dispatch: where the baseline lacks AVX2, gcc and clang compile the
   kernels a second time for AVX2 (target pragmas; their intrinsics need no
   -m flag), MSVC likewise (its intrinsics need no flag or pragma), and each
   BVH picks the path its CPU runs. */
#if HAIROBB__SSE && !HAIROBB__AVX2 && !defined(HAIROBB_NO_DISPATCH) && \
    (((defined(__x86_64__) || defined(__i386__)) && \
      ((defined(__clang__) && __clang_major__ >= 4) || (!defined(__clang__) && defined(__GNUC__) && __GNUC__ >= 5))) || \
     (defined(_MSC_VER) && !defined(__clang__) && defined(_M_X64)))
#define HAIROBB__DISPATCH 1
#include <immintrin.h>
#else
#define HAIROBB__DISPATCH 0
#endif

/* The build's threads (HAIROBB_NO_THREADS: none): Win32's on Windows
   (Vista and later: slim reader/writer locks and condition variables),
   POSIX threads on other systems that have them. Each has the same few
   calls below: a lock, condition variables, threads started and joined,
   the number of cores. */
#if !defined(HAIROBB_NO_THREADS) && defined(_WIN32)
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#define HAIROBB__LEAN_DEFINED
#endif
#ifndef NOMINMAX
#define NOMINMAX   /* no min and max macros from windows.h */
#define HAIROBB__NOMINMAX_DEFINED
#endif
#include <windows.h>
#ifdef HAIROBB__LEAN_DEFINED
#undef WIN32_LEAN_AND_MEAN
#undef HAIROBB__LEAN_DEFINED
#endif
#ifdef HAIROBB__NOMINMAX_DEFINED
#undef NOMINMAX
#undef HAIROBB__NOMINMAX_DEFINED
#endif
#define HAIROBB__THREADS 1
typedef SRWLOCK hairobb__mutex;
typedef CONDITION_VARIABLE hairobb__cond;
typedef HANDLE hairobb__thread;
#define HAIROBB__THREAD_FN(name, arg) static DWORD WINAPI name(LPVOID arg)
#define HAIROBB__THREAD_END return 0
static int hairobb__mutex_init(hairobb__mutex *m) { InitializeSRWLock(m); return 0; }
static void hairobb__mutex_destroy(hairobb__mutex *m) { (void)m; }
static void hairobb__mutex_lock(hairobb__mutex *m) { AcquireSRWLockExclusive(m); }
static void hairobb__mutex_unlock(hairobb__mutex *m) { ReleaseSRWLockExclusive(m); }
static int hairobb__cond_init(hairobb__cond *c) { InitializeConditionVariable(c); return 0; }
static void hairobb__cond_destroy(hairobb__cond *c) { (void)c; }
static void hairobb__cond_wait(hairobb__cond *c, hairobb__mutex *m) { SleepConditionVariableSRW(c, m, INFINITE, 0); }
static void hairobb__cond_signal(hairobb__cond *c) { WakeConditionVariable(c); }
static void hairobb__cond_broadcast(hairobb__cond *c) { WakeAllConditionVariable(c); }
static int hairobb__thread_start(hairobb__thread *t, LPTHREAD_START_ROUTINE fn, void *arg)
{
    *t = CreateThread(NULL, 0, fn, arg, 0, NULL);
    return *t ? 0 : -1;
}
static void hairobb__thread_join(hairobb__thread t)
{
    WaitForSingleObject(t, INFINITE);
    CloseHandle(t);
}
/* logical processors of the calling thread's processor group (at most 64) */
static long hairobb__core_count(void)
{
    SYSTEM_INFO info;
    GetSystemInfo(&info);
    return (long)info.dwNumberOfProcessors;
}
#elif !defined(HAIROBB_NO_THREADS) && (defined(__unix__) || defined(__APPLE__))
#include <pthread.h>
#include <unistd.h>
#define HAIROBB__THREADS 1
typedef pthread_mutex_t hairobb__mutex;
typedef pthread_cond_t hairobb__cond;
typedef pthread_t hairobb__thread;
#define HAIROBB__THREAD_FN(name, arg) static void *name(void *arg)
#define HAIROBB__THREAD_END return NULL
static int hairobb__mutex_init(hairobb__mutex *m) { return pthread_mutex_init(m, NULL); }
static void hairobb__mutex_destroy(hairobb__mutex *m) { pthread_mutex_destroy(m); }
static void hairobb__mutex_lock(hairobb__mutex *m) { pthread_mutex_lock(m); }
static void hairobb__mutex_unlock(hairobb__mutex *m) { pthread_mutex_unlock(m); }
static int hairobb__cond_init(hairobb__cond *c) { return pthread_cond_init(c, NULL); }
static void hairobb__cond_destroy(hairobb__cond *c) { pthread_cond_destroy(c); }
static void hairobb__cond_wait(hairobb__cond *c, hairobb__mutex *m) { pthread_cond_wait(c, m); }
static void hairobb__cond_signal(hairobb__cond *c) { pthread_cond_signal(c); }
static void hairobb__cond_broadcast(hairobb__cond *c) { pthread_cond_broadcast(c); }
static int hairobb__thread_start(hairobb__thread *t, void *(*fn)(void *), void *arg) { return pthread_create(t, NULL, fn, arg); }
static void hairobb__thread_join(hairobb__thread t) { pthread_join(t, NULL); }
static long hairobb__core_count(void) { return sysconf(_SC_NPROCESSORS_ONLN); }
#else
#define HAIROBB__THREADS 0
#endif

/* Compiler spellings, in one place: gcc and clang (and clang-cl), MSVC,
   and plain C for any other compiler (correct, slower). Helpers the
   kernels call are always inlined: inside the AVX2 copy they are then
   compiled for AVX2 too. A call from AVX2 code into SSE code (without the
   VEX encoding) pays a transition penalty on every call (the pieces
   intersector and the shared-rotation nodes ran at half speed).
   HAIROBB__NOINLINE, HAIROBB__COLD and HAIROBB__TARGET_AVX2 (MSVC needs
   none to use AVX2 intrinsics) open a declaration; HAIROBB__PREFETCH is
   only a hint. */
#if defined(__GNUC__) || defined(__clang__)
#define HAIROBB__INLINE static inline __attribute__((always_inline))
#define HAIROBB__NOINLINE __attribute__((noinline))
#define HAIROBB__COLD __attribute__((noinline, cold))
#define HAIROBB__TARGET_AVX2 __attribute__((target("avx2")))
#define HAIROBB__LIKELY(x) __builtin_expect(!!(x), 1)
#define HAIROBB__PREFETCH(address) __builtin_prefetch(address)
#elif defined(_MSC_VER)
#include <intrin.h>
#define HAIROBB__INLINE static __forceinline
#define HAIROBB__NOINLINE __declspec(noinline)
#define HAIROBB__COLD __declspec(noinline)
#define HAIROBB__TARGET_AVX2
#define HAIROBB__LIKELY(x) (x)
#if HAIROBB__SSE
#define HAIROBB__PREFETCH(address) _mm_prefetch((const char *)(address), _MM_HINT_T0)
#endif
#else
#define HAIROBB__INLINE static inline
#define HAIROBB__NOINLINE
#define HAIROBB__COLD
#define HAIROBB__TARGET_AVX2
#define HAIROBB__LIKELY(x) (x)
#endif
#ifndef HAIROBB__PREFETCH
#define HAIROBB__PREFETCH(address) ((void)(address))
#endif

#ifdef __cplusplus
#define HAIROBB__CAST(type, x) (static_cast<type>(x))
#else
#define HAIROBB__CAST(type, x) ((type)(x))
#endif

#if defined(__linux__) && !defined(HAIROBB_NO_HUGE_PAGES)
#include <sys/mman.h>
#endif

/* HAIROBB_MALLOC for blocks a build or load fills whole: from 4 MB on, the
   2 MB pages inside the block are advised to be huge (HAIROBB_NO_HUGE_PAGES).
   Only a hint: nothing changes where the kernel ignores it. */
static void *hairobb__malloc_large(size_t bytes, void *user)
{
    void *block = HAIROBB_MALLOC(bytes, user);
    (void)user;
#if defined(__linux__) && defined(MADV_HUGEPAGE) && !defined(HAIROBB_NO_HUGE_PAGES)
    if (block && bytes >= ((size_t)4 << 20)) {
        const size_t huge = (size_t)2 << 20, skip = (huge - (size_t)((uintptr_t)block & (huge - 1))) & (huge - 1);
        size_t length = (bytes - skip) & ~(huge - 1);
        if (length) (void)madvise(HAIROBB__CAST(unsigned char *, block) + skip, length, MADV_HUGEPAGE);
    }
#endif
    return block;
}

/* ------------------------------------------------------------------------ */
/* >>defaults  Limits, defaults, cost model, node references                */
/* ------------------------------------------------------------------------ */
#ifndef HAIROBB_NODE_WIDTH             /* children per node: 4 or 8 */
#if HAIROBB__AVX || HAIROBB__DISPATCH
/* one AVX register per node test: with AVX2, 8-wide trees trace faster
   than 4-wide, with SSE2 slower (docs/benchmarking.md); CPUs without
   AVX2 are few. */
#define HAIROBB_NODE_WIDTH 8
#else
#define HAIROBB_NODE_WIDTH 4
#endif
#endif
#define HAIROBB__W HAIROBB_NODE_WIDTH
/* What a zero (or AUTO) field of hairobb_build_options means: the defaults,
   set in one place (hairobb__resolve_options). The layout and the heuristics
   are the bench's choice (its ablation, docs/benchmarking.md). */
#define HAIROBB__DEFAULT_MAX_LEAF 4u
#define HAIROBB__DEFAULT_CANDIDATES 2u
#define HAIROBB__DEFAULT_PIECES 8u
#define HAIROBB__DEFAULT_SPLIT_BUDGET 0.25f
#define HAIROBB__DEFAULT_OBB_LAYOUT HAIROBB_OBB_COMPRESSED_PER_CHILD
#define HAIROBB__DEFAULT_SPATIAL_SPLITS HAIROBB_OFF
#define HAIROBB__DEFAULT_CLUSTERING HAIROBB_OFF
#define HAIROBB__DEFAULT_BEZIER_COPY HAIROBB_ON
#define HAIROBB__DEFAULT_VERIFY_HAIR HAIROBB_ON
#define HAIROBB__MAX_THREADS 256u
#define HAIROBB__MAX_TIME_STEPS 65535u   /* a saved BVH keeps them in 16 bits' range */
#define HAIROBB__MAX_SPLIT_BUDGET 4.0f
/* A range a full node could not split further becomes a leaf, not a node of
   its own, up to this many segments: much less memory at equal or
   better speed (docs/benchmarking.md, leaf size). */
#define HAIROBB__FULL_NODE_LEAF (HAIROBB__W == 8 ? 3u : 2u)
#define HAIROBB__BINS 16
#define HAIROBB__MAX_PIECES 16
#define HAIROBB__MAX_LEAF 15
#define HAIROBB__MAX_CANDIDATES 16
#define HAIROBB__MAX_COORD 1e18f        /* beyond this, box areas overflow float */
#define HAIROBB__SAH_DEPTH 40           /* deeper nodes split at the median, so depth stays bounded */
#define HAIROBB__STACK ((HAIROBB__W - 1) * (HAIROBB__SAH_DEPTH + 32) + 1)  /* pushes per level x depth */
#ifndef HAIROBB__SAMPLE
/* The per-child compressed layout keeps float boxes in AABB nodes (the top
   of the tree) and in OBB nodes over more than this many references: every
   ray passes there, and they are few: faster primary rays for under a
   byte per segment. */
#define HAIROBB__FLOAT_NODES 256
#define HAIROBB__TASKS 64               /* about this many subtrees are built as tasks (threads) */
#define HAIROBB__TASK_MIN 1024          /* of at least this many references, unless the input is smaller */
#define HAIROBB__SAMPLE 16              /* segments sampled to rank hair-space candidates: 64 built slower, traced the same */
#endif
/* Relative costs of testing one child box and intersecting one segment.
   OBB over AABB is measured in instructions a node visit (callgrind): an
   OBB node of any layout costs about 1.6-1.7 AABB node visits (the ray
   transform). */
#ifndef HAIROBB__COST_AABB
#define HAIROBB__COST_AABB 1.0f
#endif
#ifndef HAIROBB__COST_OBB
#define HAIROBB__COST_OBB 1.6f
#endif
#ifndef HAIROBB__COST_SEGMENT
#define HAIROBB__COST_SEGMENT 4.0f
#endif

/* Node references: low 4 bits type; inner nodes: byte offset (a multiple of 16);
   leaves: first index into leaf_prims << 8 | count << 4 (while building:
   first position of ids). */
#define HAIROBB__REF_AABB 0u
#define HAIROBB__REF_OBB 1u
#define HAIROBB__REF_LEAF 2u
#define HAIROBB__REF_EMPTY 3u
#define HAIROBB__REF_ROTATED 4u
#define HAIROBB__REF_QAABB 5u          /* compressed node, axis-aligned */
#define HAIROBB__REF_QOBB 6u           /* compressed node, rotated */
#define HAIROBB__REF_QOBB_PER_CHILD 7u /* compressed node, a rotation per child */
#define HAIROBB__REF_TASK 8u           /* builder only: index << 4 of a subtree built as a task */
/* Moving hair's compressed nodes (motion blur): the still type 4 below,
   then a second set of byte planes, the boxes at time 1 (linear bounds) */
#define HAIROBB__REF_QAABB_MB 9u
#define HAIROBB__REF_QOBB_MB 10u
#define HAIROBB__REF_QOBB_PER_CHILD_MB 11u
#define HAIROBB__REF_TYPE(ref) ((unsigned)((ref) & 15u))
/* Inner node ref in node memory: every reader of a node (the traversal,
   refit, the SAH cost, the loader's walk) finds it here. A leaf has no
   address (a one-leaf tree has no node memory). */
#define HAIROBB__NODE_OFFSET(ref) ((size_t)((ref) & ~(uint64_t)15))
#define HAIROBB__NODE_AT(nodes, ref) ((nodes) + HAIROBB__NODE_OFFSET(ref))
#define HAIROBB__MOVING(type) ((type) >= HAIROBB__REF_QAABB_MB && (type) <= HAIROBB__REF_QOBB_PER_CHILD_MB)
#define HAIROBB__STILL_TYPE(type) (HAIROBB__MOVING(type) ? (type) - 4u : (type))

/* ------------------------------------------------------------------------ */
/* >>vector  Small vector helpers                                           */
/* ------------------------------------------------------------------------ */
HAIROBB__INLINE float hairobb__minf(float a, float b) { return a < b ? a : b; }
HAIROBB__INLINE float hairobb__maxf(float a, float b) { return a > b ? a : b; }
HAIROBB__INLINE float hairobb__dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Rows 0,1 span the plane orthogonal to n (unit), row 2 = n, right-handed
   (row0 x row1 = row2). Branch-free basis of Duff et al. 2017. */
static void hairobb__frame_from_direction(const float n[3], float frame[9])
{
    float sign = n[2] >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n[2]);
    float b = n[0] * n[1] * a;
    frame[0] = 1.0f + sign * n[0] * n[0] * a; frame[1] = sign * b; frame[2] = -sign * n[0];
    frame[3] = b; frame[4] = sign + n[1] * n[1] * a; frame[5] = -n[1];
    frame[6] = n[0]; frame[7] = n[1]; frame[8] = n[2];
}

static void hairobb__identity_frame(float frame[9])
{
    memset(frame, 0, 9 * sizeof(float));
    frame[0] = frame[4] = frame[8] = 1.0f;
}

/* Widens [lower, upper] by 2-4 float ulps of the largest magnitude involved:
   the rounding of the box's own computation. Rounding in the traversal
   scales with the distance from the ray origin to the box (OBBs are stored
   relative to a centre near them) and is covered by HAIROBB__FAR_SCALE. */
static void hairobb__pad_box(float lower[3], float upper[3])
{
    int k;
    for (k = 0; k < 3; ++k) {
        float mag = hairobb__maxf(hairobb__maxf(fabsf(lower[k]), fabsf(upper[k])), upper[k] - lower[k]);
        float pad = mag * (1.0f / 4194304.0f) + 1e-30f;  /* 2^-22 relative: 2-4 ulps */
        lower[k] -= pad;
        upper[k] += pad;
    }
}

static float hairobb__half_area(const float lower[3], const float upper[3])
{
    float dx = upper[0] - lower[0], dy = upper[1] - lower[1], dz = upper[2] - lower[2];
    return dx * dy + dy * dz + dz * dx;
}

static void hairobb__box_empty(float lower[3], float upper[3])
{
    int k;
    for (k = 0; k < 3; ++k) { lower[k] = FLT_MAX; upper[k] = -FLT_MAX; }
}

static inline void hairobb__box_grow(float lower[3], float upper[3], const float lo[3], const float hi[3])
{
    /* all loads before any store: the arrays may alias, and the compiler would reload */
    float l0 = lo[0], l1 = lo[1], l2 = lo[2], h0 = hi[0], h1 = hi[1], h2 = hi[2];
    float a0 = lower[0], a1 = lower[1], a2 = lower[2], b0 = upper[0], b1 = upper[1], b2 = upper[2];
    lower[0] = hairobb__minf(a0, l0); lower[1] = hairobb__minf(a1, l1); lower[2] = hairobb__minf(a2, l2);
    upper[0] = hairobb__maxf(b0, h0); upper[1] = hairobb__maxf(b1, h1); upper[2] = hairobb__maxf(b2, h2);
}

/* Cubic Bezier value and first two derivatives at u. */
HAIROBB__INLINE float hairobb__bezier(const float c[4], float u, float *d1, float *d2)
{
    float s = 1.0f - u;
    float e0 = c[1] - c[0], e1 = c[2] - c[1], e2 = c[3] - c[2];
    if (d1) *d1 = 3.0f * (s * s * e0 + 2.0f * u * s * e1 + u * u * e2);
    if (d2) *d2 = 6.0f * (s * (e1 - e0) + u * (e2 - e1));
    return s * s * s * c[0] + 3.0f * u * s * s * c[1] + 3.0f * u * u * s * c[2] + u * u * u * c[3];
}

/* Coordinate k of a segment (control points x, y, z, r each) at u. */
static float hairobb__bezier4(const float *cp, int k, float u)
{
    float c[4];
    c[0] = cp[k]; c[1] = cp[4 + k]; c[2] = cp[8 + k]; c[3] = cp[12 + k];
    return hairobb__bezier(c, u, NULL, NULL);
}

HAIROBB__INLINE int hairobb__lowest_bit(unsigned bits)
{
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_ctz(bits);
#elif defined(_MSC_VER)
    unsigned long index;
    _BitScanForward(&index, bits);
    return (int)index;
#else
    int i = 0;
    while (!(bits & 1u)) { bits >>= 1; ++i; }
    return i;
#endif
}

/* The highest set bit's index; bits != 0. */
HAIROBB__INLINE int hairobb__highest_bit(unsigned bits)
{
#if defined(__GNUC__) || defined(__clang__)
    return 31 - __builtin_clz(bits);
#elif defined(_MSC_VER)
    unsigned long index;
    _BitScanReverse(&index, bits);
    return (int)index;
#else
    int i = 31;
    while (!(bits & 0x80000000u)) { bits <<= 1; --i; }
    return i;
#endif
}

/* ------------------------------------------------------------------------ */
/* >>bvh  The BVH object                                                    */
/* ------------------------------------------------------------------------ */
/* What shapes a tree and its intersector: the build's resolved options,
   which hairobb_save records and hairobb_load reads back. */
typedef struct hairobb__tree_settings {
    hairobb_precision precision;
    hairobb_shape shape;
    int end_caps, cull_back_faces;    /* round curves only (0 for ribbons) */
    hairobb_node_policy policy;
    hairobb_obb_layout obb_layout;
    unsigned max_leaf_size, pieces;
} hairobb__tree_settings;

struct hairobb_bvh {
    const float *vertices;            /* the caller's control points, in basis (NULL after the build
                                         where the copy made them unneeded: other bases) */
    const uint32_t *indices;          /* the caller's, or their copy (owned_indices) */
    size_t segment_count;
    /* the copy (bezier_copy ON, static hair): each leaf reference's Bezier
       control points, 16 floats, in leaf_prims' order, on 64-byte lines
       inside points_allocation; point_refs[prim] is one reference of
       each segment, for reads by segment id. NULL without the copy. */
    void *points_allocation;
    float *leaf_points;
    uint32_t *point_refs;
    /* without the copy (bezier_copy OFF, moving hair): indices[leaf_prims[i]]
       in leaf order, so that a leaf finds the caller's points with no load
       waiting for indices[prim] (a dependent miss at scale). NULL with the copy. */
    uint32_t *leaf_offsets;
    uint32_t *owned_indices;          /* other bases with the copy: the caller's indices, for hairobb_refit */
    hairobb_filter_fn hit_filter, occluded_filter;
    void *hit_filter_user, *occluded_filter_user;
    void *allocator_user;
    void *node_allocation;            /* what HAIROBB_MALLOC returned */
    unsigned char *nodes;             /* 64-byte aligned inside node_allocation */
    size_t node_bytes;
    uint32_t *leaf_prims;             /* segment ids, leaves index ranges of it */
    size_t leaf_prim_count;
    float *leaf_ranges;               /* u0, u1 of each leaf_prims entry where spatial splits clipped some; else NULL */
    /* what hairobb_refit needs: the input's size and basis, the caller's
       indices (copied after the curves for other bases), the build's threads */
    size_t vertex_count;
    hairobb_basis basis;
    const uint32_t *source_indices;
    unsigned threads;
    hairobb_parallel_for_fn parallel_for;
    void *parallel_for_user;
    int refitted;                     /* build_sah_cost below is the tree's as built */
    double build_sah_cost;
    uint64_t root;
    float lower[3], upper[3];
    hairobb_precision precision;
    hairobb_shape shape;
    int end_caps, cull_back_faces;    /* round curves: flat caps at free ends; entries only */
    /* what hairobb_save records besides: the build's resolved options */
    hairobb_node_policy policy;
    hairobb_obb_layout obb_layout;
    unsigned max_leaf_size;
    hairobb_simd simd;                /* the kernels' path */
    int pieces, piece_chunks;         /* linear pieces; 8-lane chunks of them */
    unsigned chunk_valid[2];          /* lanes holding real pieces */
    /* Bernstein weights of the pieces' start and end points: [chunk][start/end][basis][lane] */
    float piece_weights[2][2][4][8];
    hairobb_stats stats;
    /* how vertices and indices hold segments: the caller's arrays in
       basis, with tangents */
    hairobb_basis point_basis;
    const float *tangents;
    /* motion blur: time_steps >= 2 arrays (vertices = time_vertices[0]),
       the pointers owned; 0 for a static BVH */
    unsigned time_steps;
    const float **time_vertices;
    int points_in_place;              /* static Bezier input: the caller's points as they are */
    int copy_points;                  /* bezier_copy resolved: ON for static hair, else 0 */
    /* several groups (hairobb_build_groups, >>groups): the BVH is built
       over its own concatenation of the groups' arrays (group_vertices,
       group_indices, ...), group g holding segments [group_first[g],
       group_first[g + 1]) and vertices [vertex_first[g], vertex_first[g
       + 1]); group_first NULL for hairobb_build's one group */
    uint32_t group_count;
    uint32_t *group_first, *group_mask;
    size_t *vertex_first;
    void **group_user;
    uint32_t group_mask_and;          /* the groups' masks ANDed: a ray mask sharing a bit with it excludes none */
    float *group_vertices, *group_tangents, *group_steps;   /* the concatenation: points, tangents, every step's points */
    uint32_t *group_indices;
    const float **group_step_list;    /* time_steps pointers into group_steps */
    unsigned char *group_shape;       /* each group's hairobb_shape */
    uint32_t *round_bits;             /* groups of both shapes (MIXED SHAPES): a bit a segment, set for a tube; else NULL */
};

/* The group of segment prim (>>groups): the last g with group_first[g] <=
   prim, by halving (groups are few next to segments; only a hit's ids, a
   mask that excludes groups, and joints and skips at group ends ask). 0
   for hairobb_build's one group. */
HAIROBB__INLINE uint32_t hairobb__group_of(const hairobb_bvh *bvh, uint32_t prim)
{
    uint32_t lo = 0, hi;
    if (!bvh->group_first) return 0;
    hi = bvh->group_count;   /* group_first[lo] <= prim < group_first[hi] */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (bvh->group_first[mid] <= prim) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* Whether segment prim is a tube: the BVH's shape, and where its groups
   mix shapes (such a BVH is round), the segment's bit: a ribbon BVH asks
   as before, a round one loads one pointer more. */
HAIROBB__INLINE int hairobb__is_tube(const hairobb_bvh *bvh, uint32_t prim)
{
    return bvh->shape == HAIROBB_SHAPE_ROUND && (!bvh->round_bits || ((bvh->round_bits[prim >> 5] >> (prim & 31u)) & 1u));
}


/* The Bezier control points of segment prim as traced at time: defined
   with the kernels ("Segment points as traced"), which read them per leaf. */
HAIROBB__INLINE const float *hairobb__segment_points(const hairobb_bvh *bvh, uint32_t prim, float time, float scratch[16]);
/* A segment of another basis in Bezier form: defined with the kernels
   ("Segment points as traced"), in their 4-wide vectors; the builder, the
   loader, a refit and the .hair reader convert with the same function. */
HAIROBB__INLINE void hairobb__to_bezier(hairobb_basis basis, const float *p, const float *t, float b[16]);

/* ------------------------------------------------------------------------ */
/* >>input  Input: results, options, validation, curve bases, bounds        */
/* ------------------------------------------------------------------------ */
HAIROBB_DEF const char *hairobb_result_string(hairobb_result r)
{
    switch (r) {
    case HAIROBB_OK: return "ok";
    case HAIROBB_ERROR_INVALID_ARGUMENT: return "invalid argument (NULL pointer, zero segments or bad option)";
    case HAIROBB_ERROR_INDEX_OUT_OF_RANGE: return "segment index out of range (its last control point past the vertices)";
    case HAIROBB_ERROR_INVALID_GEOMETRY: return "invalid geometry (NaN, infinite or huge coordinate, or negative radius)";
    case HAIROBB_ERROR_OUT_OF_MEMORY: return "out of memory";
    case HAIROBB_ERROR_TOO_LARGE: return "input too large (size overflow or more than 2^32-1 segments)";
    case HAIROBB_ERROR_CANCELLED: return "build cancelled by the progress callback";
    case HAIROBB_ERROR_INVALID_FILE: return "invalid .hair data or saved BVH (magic, flags, counts, sizes, checksum or structure)";
    case HAIROBB_ERROR_IO: return "file could not be opened, read or written";
    case HAIROBB_ERROR_UNSUPPORTED: return "not supported: SIMD path (options.simd) this build or CPU lacks, or a BVH saved by "
                                           "another format version, node width or byte order";
    case HAIROBB_ERROR_MISMATCH: return "saved BVH loaded over other hair (vertices, indices, segment count or basis)";
    }
    return "unknown hairobb_result";
}

HAIROBB_DEF const char *hairobb_simd_string(hairobb_simd simd)
{
    switch (simd) {
    case HAIROBB_SIMD_AUTO: return "auto";
    case HAIROBB_SIMD_NONE: return "plain C";
    case HAIROBB_SIMD_SSE2: return "SSE2";
    case HAIROBB_SIMD_SSE41: return "SSE4.1";
    case HAIROBB_SIMD_AVX: return "AVX";
    case HAIROBB_SIMD_AVX2: return "AVX2";
    case HAIROBB_SIMD_NEON: return "NEON";
    }
    return "unknown hairobb_simd";
}

/* The path options.simd asks for: the baseline (what the compiler targets),
   or AVX2 where the kernels were compiled for it too and the CPU (and its
   operating system) runs it. */
static hairobb_result hairobb__choose_simd(hairobb_simd requested, hairobb_simd *chosen)
{
    int avx2 = 0;
#if HAIROBB__DISPATCH && defined(_MSC_VER) && !defined(__clang__)
    /* AVX2 (leaf 7), and the operating system saving the YMM registers:
       OSXSAVE and AVX (leaf 1), XMM and YMM state enabled in XCR0 */
    int info[4];
    __cpuid(info, 0);
    if (info[0] >= 7) {
        __cpuid(info, 1);
        if ((info[2] & (1 << 27)) && (info[2] & (1 << 28)) && (_xgetbv(0) & 6u) == 6u) {
            __cpuidex(info, 7, 0);
            avx2 = (info[1] & (1 << 5)) != 0;
        }
    }
#elif HAIROBB__DISPATCH
    __builtin_cpu_init();
    avx2 = __builtin_cpu_supports("avx2") != 0;
#endif
    *chosen = HAIROBB__BASELINE_SIMD;
    if (requested == HAIROBB_SIMD_AUTO || (requested == HAIROBB_SIMD_AVX2 && avx2)) {
        if (avx2) *chosen = HAIROBB_SIMD_AVX2;
        return HAIROBB_OK;
    }
    return requested == HAIROBB__BASELINE_SIMD ? HAIROBB_OK : HAIROBB_ERROR_UNSUPPORTED;
}

/* Which options the caller reads: a build all of them, a load those that do
   not shape the tree (the rest are the saved BVH's). */
enum { HAIROBB__FOR_BUILD, HAIROBB__FOR_LOAD };

/* The first field of o (NULL: all zero, valid) out of range among those
   the purpose reads, by name; NULL where all are in range. The one place
   option values are judged: hairobb_check_options reports it, the build
   and the load refuse it (INVALID_ARGUMENT). */
static const char *hairobb__bad_option(const hairobb_build_options *o, int purpose)
{
    if (!o) return NULL;
    if ((unsigned)o->basis > HAIROBB_BASIS_LINEAR) return "basis";
    if ((o->basis == HAIROBB_BASIS_HERMITE) != (o->tangents != NULL)) return "tangents";   /* Hermite needs them, no other basis takes them */
    if ((unsigned)o->simd > HAIROBB_SIMD_NEON) return "simd";
    if (o->threads > HAIROBB__MAX_THREADS) return "threads";
    if ((unsigned)o->bezier_copy > HAIROBB_OFF) return "bezier_copy";
    if (o->time_steps >= 2) {
        unsigned k;
        if (o->basis == HAIROBB_BASIS_HERMITE) return "time_steps";   /* moving Hermite tangents are not taken */
        if (o->time_steps > HAIROBB__MAX_TIME_STEPS) return "time_steps";
        if (!o->time_vertices) return "time_vertices";
        for (k = 0; k < o->time_steps; ++k)
            if (!o->time_vertices[k]) return "time_vertices";
    }
    /* read by a load only, but judged for both: hairobb_check_options
       names every field out of range that either call refuses */
    if ((unsigned)o->verify_hair > HAIROBB_OFF) return "verify_hair";
    if (purpose == HAIROBB__FOR_LOAD) return NULL;
    if ((unsigned)o->nodes > HAIROBB_NODES_OBB_ONLY) return "nodes";
    if ((unsigned)o->precision > HAIROBB_PRECISION_PIECES) return "precision";
    if ((unsigned)o->obb_layout > HAIROBB_OBB_COMPRESSED_PER_CHILD) return "obb_layout";
    if ((unsigned)o->spatial_splits > HAIROBB_OFF) return "spatial_splits";
    if ((unsigned)o->clustering > HAIROBB_OFF) return "clustering";
    if (!(o->spatial_split_budget >= 0.0f && o->spatial_split_budget <= HAIROBB__MAX_SPLIT_BUDGET)) return "spatial_split_budget";
    if (o->max_leaf_size > HAIROBB__MAX_LEAF) return "max_leaf_size";
    if (o->hair_space_candidates > HAIROBB__MAX_CANDIDATES) return "hair_space_candidates";
    if (o->curve_pieces > HAIROBB__MAX_PIECES) return "curve_pieces";
    if ((unsigned)o->shape > HAIROBB_SHAPE_ROUND) return "shape";
    if (o->shape == HAIROBB_SHAPE_ROUND && o->precision == HAIROBB_PRECISION_PIECES) return "precision";   /* tubes are exact only */
    if ((unsigned)o->end_caps > HAIROBB_OFF) return "end_caps";
    if ((unsigned)o->back_faces > HAIROBB_OFF) return "back_faces";
    return NULL;
}

HAIROBB_DEF const char *hairobb_check_options(const hairobb_build_options *options)
{
    return hairobb__bad_option(options, HAIROBB__FOR_BUILD);
}

HAIROBB_DEF hairobb_build_options hairobb_default_options(void)
{
    hairobb_build_options options;
    memset(&options, 0, sizeof options);
    return options;
}

/* The options as given (NULL: all zero) into *opt, every zero or AUTO field
   that stands for a default set to it; INVALID_ARGUMENT for a value out of
   range among the fields the purpose reads. */
static hairobb_result hairobb__resolve_options(const hairobb_build_options *given, int purpose, hairobb_build_options *opt)
{
    if (hairobb__bad_option(given, purpose)) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (given) *opt = *given; else memset(opt, 0, sizeof *opt);
    if (opt->bezier_copy == HAIROBB_AUTO) opt->bezier_copy = HAIROBB__DEFAULT_BEZIER_COPY;
    if (opt->verify_hair == HAIROBB_AUTO) opt->verify_hair = HAIROBB__DEFAULT_VERIFY_HAIR;
    if (purpose == HAIROBB__FOR_LOAD) return HAIROBB_OK;
    if (opt->max_leaf_size == 0) opt->max_leaf_size = HAIROBB__DEFAULT_MAX_LEAF;
    if (opt->hair_space_candidates == 0) opt->hair_space_candidates = HAIROBB__DEFAULT_CANDIDATES;
    if (opt->curve_pieces == 0) opt->curve_pieces = HAIROBB__DEFAULT_PIECES;
    if (opt->spatial_split_budget == 0.0f) opt->spatial_split_budget = HAIROBB__DEFAULT_SPLIT_BUDGET;
    if (opt->obb_layout == HAIROBB_OBB_DEFAULT) opt->obb_layout = HAIROBB__DEFAULT_OBB_LAYOUT;
    if (opt->spatial_splits == HAIROBB_AUTO) opt->spatial_splits = HAIROBB__DEFAULT_SPATIAL_SPLITS;
    if (opt->clustering == HAIROBB_AUTO) opt->clustering = HAIROBB__DEFAULT_CLUSTERING;
    return HAIROBB_OK;
}

/* Control points a segment of the basis reads from indices[i] on. */
HAIROBB__INLINE size_t hairobb__basis_points(hairobb_basis basis)
{
    return basis == HAIROBB_BASIS_HERMITE || basis == HAIROBB_BASIS_LINEAR ? 2 : 4;
}

/* points per segment from indices[i]; tangents (Hermite) checked alike. */
static hairobb_result hairobb__validate(const float *vertices, size_t vertex_count, const uint32_t *indices,
                                        size_t segment_count, size_t points, const float *tangents)
{
    size_t i, k;
    const float max_coord = HAIROBB__MAX_COORD;
    uint32_t max_bits;
    memcpy(&max_bits, &max_coord, sizeof max_bits);
    if (segment_count > 0xffffffffu || vertex_count > (size_t)-1 / (4 * sizeof(float)))
        return HAIROBB_ERROR_TOO_LARGE;
    for (i = 0; i < segment_count; ++i) {
        if (vertex_count < points || indices[i] > vertex_count - points) return HAIROBB_ERROR_INDEX_OUT_OF_RANGE;
    }
    for (i = 0; i < segment_count; ++i) {
        const float *cp = vertices + 4 * (size_t)indices[i], *tp = tangents ? tangents + 4 * (size_t)indices[i] : NULL;
        /* On the bits, without a branch per float (a refit validates every
           frame): |x| <= HAIROBB__MAX_COORD is (bits & 0x7fffffff) <= the
           bound's bits, false for NaN and Inf too; a radius < 0 (-0 is
           not) has bits above 0x80000000. */
        uint32_t bad = 0, bits[4];
        for (k = 0; k < points; ++k) {
            memcpy(bits, cp + 4 * k, sizeof bits);
            bad |= ((bits[0] & 0x7fffffffu) > max_bits) | ((bits[1] & 0x7fffffffu) > max_bits) |
                   ((bits[2] & 0x7fffffffu) > max_bits) | ((bits[3] & 0x7fffffffu) > max_bits) | (bits[3] > 0x80000000u);
            if (!tp) continue;
            memcpy(bits, tp + 4 * k, sizeof bits);
            bad |= ((bits[0] & 0x7fffffffu) > max_bits) | ((bits[1] & 0x7fffffffu) > max_bits) |
                   ((bits[2] & 0x7fffffffu) > max_bits) | ((bits[3] & 0x7fffffffu) > max_bits);
        }
        if (bad) return HAIROBB_ERROR_INVALID_GEOMETRY;
    }
    return HAIROBB_OK;
}

/* Motion blur's input (hairobb_build and hairobb_load): *steps = 0 for a
   static BVH (time_steps 0 or 1), else every step validated as vertices
   are, and *vertices = the first step. */
static hairobb_result hairobb__validate_motion(const hairobb_build_options *opt, size_t vertex_count, const uint32_t *indices,
                                               size_t segment_count, const float **vertices, unsigned *steps)
{
    unsigned k;
    *steps = 0;
    if (opt->time_steps < 2) return HAIROBB_OK;
    /* as hairobb__bad_option judges them; hairobb_refit_motion comes here alone */
    if (!opt->time_vertices || opt->basis == HAIROBB_BASIS_HERMITE || opt->time_steps > HAIROBB__MAX_TIME_STEPS)
        return HAIROBB_ERROR_INVALID_ARGUMENT;
    for (k = 0; k < opt->time_steps; ++k)
        if (!opt->time_vertices[k]) return HAIROBB_ERROR_INVALID_ARGUMENT;
    for (k = 0; k < opt->time_steps; ++k) {
        hairobb_result result = hairobb__validate(opt->time_vertices[k], vertex_count, indices, segment_count,
                                                  hairobb__basis_points(opt->basis), NULL);
        if (result != HAIROBB_OK) return result;
    }
    *vertices = opt->time_vertices[0];
    *steps = opt->time_steps;
    return HAIROBB_OK;
}

/* The hair arrays hairobb_build and hairobb_load take, validated; moving
   hair: *vertices = its first step, *steps = time_steps (else 0). */
static hairobb_result hairobb__validate_hair(const hairobb_build_options *opt, const float **vertices, size_t vertex_count,
                                             const uint32_t *indices, size_t segment_count, unsigned *steps)
{
    if (opt->time_steps < 2) {
        hairobb_result result = hairobb__validate(*vertices, vertex_count, indices, segment_count,
                                                  hairobb__basis_points(opt->basis), opt->tangents);
        if (result != HAIROBB_OK) return result;
    }
    return hairobb__validate_motion(opt, vertex_count, indices, segment_count, vertices, steps);
}

/* A copy of the steps' pointers (the BVH's, freed with it); NULL when out of memory. */
static const float **hairobb__copy_steps(const float *const *time_vertices, unsigned steps, void *user)
{
    const float **copy = HAIROBB__CAST(const float **, HAIROBB_MALLOC(steps * sizeof *copy, user));
    unsigned k;
    if (copy)
        for (k = 0; k < steps; ++k) copy[k] = time_vertices[k];
    return copy;
}

/* The hair a BVH traces, as hairobb_build and hairobb_load take it (arrays
   validated): the caller's arrays, read in their basis; moving hair keeps
   the steps' pointers. With the copy (hairobb__copy_points, once the
   leaves are known), other bases keep a copy of the caller's indices, so
   that their arrays may go after the build. 0: out of memory
   (hairobb_free frees what was taken). */
static int hairobb__take_hair(hairobb_bvh *bvh, const hairobb_build_options *opt, const float *vertices,
                              size_t vertex_count, const uint32_t *indices, size_t segment_count, unsigned steps)
{
    bvh->vertices = vertices;
    bvh->indices = indices;
    bvh->source_indices = indices;
    bvh->vertex_count = vertex_count;
    bvh->segment_count = segment_count;
    bvh->basis = opt->basis;
    bvh->point_basis = opt->basis;
    bvh->tangents = opt->tangents;
    if (steps) {
        bvh->time_vertices = hairobb__copy_steps(opt->time_vertices, steps, bvh->allocator_user);
        if (!bvh->time_vertices) return 0;
        bvh->time_steps = steps;
    }
    bvh->copy_points = opt->bezier_copy == HAIROBB_ON && !steps;
    if (bvh->copy_points && opt->basis != HAIROBB_BASIS_BEZIER) {
        bvh->owned_indices = HAIROBB__CAST(uint32_t *, hairobb__malloc_large(segment_count * sizeof(uint32_t), bvh->allocator_user));
        if (!bvh->owned_indices) return 0;
        memcpy(bvh->owned_indices, indices, segment_count * sizeof(uint32_t));
        bvh->indices = bvh->owned_indices;
        bvh->source_indices = bvh->owned_indices;
    }
    bvh->points_in_place = bvh->point_basis == HAIROBB_BASIS_BEZIER && !steps;
    return 1;
}

/* The bin (of HAIROBB__BINS) of coordinate x for binning from origin. */
static int hairobb__bin_of(float x, float origin, float scale)
{
    float position = (x - origin) * scale;
    /* clamped before the conversion: a float out of int's range (or NaN)
       converted to int is undefined */
    if (!(position >= 1.0f)) return 0;
    return position >= (float)(HAIROBB__BINS - 1) ? HAIROBB__BINS - 1 : (int)position;
}

/* Four float lanes for the builder's boxes (x, y, z and one unused): SSE,
   or a plain C twin computing each lane with the same operations, so both
   build the same tree. */
#if HAIROBB__SSE
typedef __m128 hairobb__b4;
HAIROBB__INLINE hairobb__b4 hairobb__b4_set1(float x) { return _mm_set1_ps(x); }
HAIROBB__INLINE hairobb__b4 hairobb__b4_set3(const float p[3]) { return _mm_setr_ps(p[0], p[1], p[2], 0.0f); }
HAIROBB__INLINE hairobb__b4 hairobb__b4_load4(const float *p) { return _mm_loadu_ps(p); }
/* a box's upper corner, box[3..5], without reading past box[5] */
HAIROBB__INLINE hairobb__b4 hairobb__b4_load_upper(const float *box)
{
    __m128 v = _mm_loadu_ps(box + 2);
    return _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 3, 2, 1));
}
HAIROBB__INLINE hairobb__b4 hairobb__b4_add(hairobb__b4 a, hairobb__b4 b) { return _mm_add_ps(a, b); }
HAIROBB__INLINE hairobb__b4 hairobb__b4_sub(hairobb__b4 a, hairobb__b4 b) { return _mm_sub_ps(a, b); }
HAIROBB__INLINE hairobb__b4 hairobb__b4_mul(hairobb__b4 a, hairobb__b4 b) { return _mm_mul_ps(a, b); }
/* a < b ? a : b and a > b ? a : b per lane, as hairobb__minf/maxf */
HAIROBB__INLINE hairobb__b4 hairobb__b4_min(hairobb__b4 a, hairobb__b4 b) { return _mm_min_ps(a, b); }
HAIROBB__INLINE hairobb__b4 hairobb__b4_max(hairobb__b4 a, hairobb__b4 b) { return _mm_max_ps(a, b); }
HAIROBB__INLINE void hairobb__b4_store3(float *p, hairobb__b4 v)
{
    _mm_storel_pi(HAIROBB__CAST(__m64 *, HAIROBB__CAST(void *, p)), v);
    _mm_store_ss(p + 2, _mm_movehl_ps(v, v));
}
HAIROBB__INLINE float hairobb__b4_lane(hairobb__b4 v, int k)
{
    float f[4];
    _mm_storeu_ps(f, v);
    return f[k];
}
/* hairobb__half_area of the box's lanes 0-2: (dx dy + dy dz) + dz dx */
HAIROBB__INLINE float hairobb__b4_half_area(hairobb__b4 lower, hairobb__b4 upper)
{
    __m128 d = _mm_sub_ps(upper, lower), p = _mm_mul_ps(d, _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 0, 2, 1)));
    return _mm_cvtss_f32(_mm_add_ss(_mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(1, 1, 1, 1))),
                                    _mm_shuffle_ps(p, p, _MM_SHUFFLE(2, 2, 2, 2))));
}
/* hairobb__bin_of of lanes 0-2 (position = (x - origin) * scale given) */
HAIROBB__INLINE void hairobb__b4_bins(hairobb__b4 position, int bin[4])
{
    __m128 in = _mm_cmpge_ps(position, _mm_set1_ps(1.0f));     /* false for NaN */
    __m128 clamped = _mm_and_ps(in, _mm_min_ps(position, _mm_set1_ps((float)(HAIROBB__BINS - 1))));
    _mm_storeu_si128(HAIROBB__CAST(__m128i *, HAIROBB__CAST(void *, bin)), _mm_cvttps_epi32(clamped));
}
#else
typedef struct hairobb__b4 { float v[4]; } hairobb__b4;
HAIROBB__INLINE hairobb__b4 hairobb__b4_set1(float x) { hairobb__b4 r; r.v[0] = r.v[1] = r.v[2] = r.v[3] = x; return r; }
HAIROBB__INLINE hairobb__b4 hairobb__b4_set3(const float p[3]) { hairobb__b4 r; r.v[0] = p[0]; r.v[1] = p[1]; r.v[2] = p[2]; r.v[3] = 0.0f; return r; }
HAIROBB__INLINE hairobb__b4 hairobb__b4_load4(const float *p) { hairobb__b4 r; memcpy(r.v, p, sizeof r.v); return r; }
HAIROBB__INLINE hairobb__b4 hairobb__b4_load_upper(const float *box)
{
    hairobb__b4 r;
    r.v[0] = box[3]; r.v[1] = box[4]; r.v[2] = box[5]; r.v[3] = box[5];
    return r;
}
#define HAIROBB__B4_LANES(name, expr) \
    HAIROBB__INLINE hairobb__b4 name(hairobb__b4 a, hairobb__b4 b) \
    { hairobb__b4 r; int k; for (k = 0; k < 4; ++k) r.v[k] = expr; return r; }
HAIROBB__B4_LANES(hairobb__b4_add, a.v[k] + b.v[k])
HAIROBB__B4_LANES(hairobb__b4_sub, a.v[k] - b.v[k])
HAIROBB__B4_LANES(hairobb__b4_mul, a.v[k] * b.v[k])
HAIROBB__B4_LANES(hairobb__b4_min, hairobb__minf(a.v[k], b.v[k]))
HAIROBB__B4_LANES(hairobb__b4_max, hairobb__maxf(a.v[k], b.v[k]))
#undef HAIROBB__B4_LANES
HAIROBB__INLINE void hairobb__b4_store3(float *p, hairobb__b4 v) { memcpy(p, v.v, 3 * sizeof(float)); }
HAIROBB__INLINE float hairobb__b4_lane(hairobb__b4 v, int k) { return v.v[k]; }
HAIROBB__INLINE float hairobb__b4_half_area(hairobb__b4 lower, hairobb__b4 upper)
{
    return hairobb__half_area(lower.v, upper.v);
}
HAIROBB__INLINE void hairobb__b4_bins(hairobb__b4 position, int bin[4])
{
    int k;
    for (k = 0; k < 3; ++k) bin[k] = hairobb__bin_of(position.v[k], 0.0f, 1.0f);
    bin[3] = 0;
}
#endif

/* A frame ready for many hairobb__segment_box calls: its columns (lane k =
   row k), so that a control point is rotated with three splats. */
typedef struct hairobb__frame_prep {
    hairobb__b4 col[3];
} hairobb__frame_prep;

static void hairobb__prepare_frame(const float frame[9], hairobb__frame_prep *p)
{
    int c;
    for (c = 0; c < 3; ++c) {
        float column[3];
        column[0] = frame[c]; column[1] = frame[3 + c]; column[2] = frame[6 + c];
        p->col[c] = hairobb__b4_set3(column);
    }
}

/* Control point p (x, y, z in lanes 0-2) in the frame: lane k =
   (frame[3k] x + frame[3k+1] y) + frame[3k+2] z. */
HAIROBB__INLINE hairobb__b4 hairobb__rotate_point(const hairobb__frame_prep *f, hairobb__b4 p)
{
#if HAIROBB__SSE
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(f->col[0], _mm_shuffle_ps(p, p, _MM_SHUFFLE(0, 0, 0, 0))),
                                 _mm_mul_ps(f->col[1], _mm_shuffle_ps(p, p, _MM_SHUFFLE(1, 1, 1, 1)))),
                      _mm_mul_ps(f->col[2], _mm_shuffle_ps(p, p, _MM_SHUFFLE(2, 2, 2, 2))));
#else
    return hairobb__b4_add(hairobb__b4_add(hairobb__b4_mul(f->col[0], hairobb__b4_set1(p.v[0])),
                                           hairobb__b4_mul(f->col[1], hairobb__b4_set1(p.v[1]))),
                           hairobb__b4_mul(f->col[2], hairobb__b4_set1(p.v[2])));
#endif
}

/* Box of a segment in a rotated frame (rows of frame are the new axes).
   The ribbon lies in the convex hull of the control points dilated by the
   largest radius (r(u) is a convex combination of the 4 radii), so the box of
   the rotated control points grown by that radius bounds it. centre, if
   given, is subtracted first; row_norms, if given, scale the radius along
   each row of a frame that is not orthonormal (a quantised one). Node boxes
   are padded for rounding once, when stored (hairobb__pad_box). Lanes 0-2
   of *lower and *upper; subtracting a zero centre and scaling by unit
   norms change no bit. */
HAIROBB__INLINE void hairobb__segment_box_v4(const float *cp, const hairobb__frame_prep *f, const float *centre,
                                             const float *row_norms, hairobb__b4 *lower, hairobb__b4 *upper)
{
    static const float zero[3] = {0.0f, 0.0f, 0.0f}, one[3] = {1.0f, 1.0f, 1.0f};
    float radius = hairobb__maxf(hairobb__maxf(cp[3], cp[7]), hairobb__maxf(cp[11], cp[15]));
    hairobb__b4 c = hairobb__b4_set3(centre ? centre : zero);
    hairobb__b4 r = hairobb__b4_mul(hairobb__b4_set1(radius), hairobb__b4_set3(row_norms ? row_norms : one));
    hairobb__b4 v0 = hairobb__rotate_point(f, hairobb__b4_sub(hairobb__b4_load4(cp), c));
    hairobb__b4 v1 = hairobb__rotate_point(f, hairobb__b4_sub(hairobb__b4_load4(cp + 4), c));
    hairobb__b4 v2 = hairobb__rotate_point(f, hairobb__b4_sub(hairobb__b4_load4(cp + 8), c));
    hairobb__b4 v3 = hairobb__rotate_point(f, hairobb__b4_sub(hairobb__b4_load4(cp + 12), c));
    *lower = hairobb__b4_sub(hairobb__b4_min(hairobb__b4_min(v0, v1), hairobb__b4_min(v2, v3)), r);
    *upper = hairobb__b4_add(hairobb__b4_max(hairobb__b4_max(v0, v1), hairobb__b4_max(v2, v3)), r);
}

HAIROBB__INLINE void hairobb__segment_box_prep(const float *cp, const hairobb__frame_prep *f, const float *centre,
                                               const float *row_norms, float lower[3], float upper[3])
{
    hairobb__b4 lo, hi;
    hairobb__segment_box_v4(cp, f, centre, row_norms, &lo, &hi);
    hairobb__b4_store3(lower, lo);
    hairobb__b4_store3(upper, hi);
}

/* ------------------------------------------------------------------------ */
/* >>hair_file  Input: Cem Yuksel's .hair files                             */
/* ------------------------------------------------------------------------ */
/* A 128-byte little-endian header ("HAIR", strand count, point count, array
   flags, default segments per strand, thickness, transparency, colour, 88
   bytes of text), then the arrays whose flags are set, in this order:
   uint16 segments per strand, float3 points, float thickness (a diameter),
   float transparency, float3 colours. */
#define HAIROBB__HAIR_HEADER 128u
#define HAIROBB__HAIR_SEGMENTS 1u
#define HAIROBB__HAIR_POINTS 2u
#define HAIROBB__HAIR_THICKNESS 4u
#define HAIROBB__HAIR_TRANSPARENCY 8u
#define HAIROBB__HAIR_COLORS 16u

/* Bytes to numbers whatever the host's byte order. */
static uint32_t hairobb__le_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float hairobb__le_float(const unsigned char *p)
{
    uint32_t bits = hairobb__le_u32(p);
    float value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

/* Where the header says each array starts, and the size it gives the whole
   file; in 64 bits, so no count can wrap. */
typedef struct hairobb__hair_layout {
    uint32_t strands, points, flags, default_segments;
    uint64_t segments_at, points_at, thickness_at, transparency_at, colors_at, size;
} hairobb__hair_layout;

static hairobb_result hairobb__hair_layout_of(const unsigned char *header, hairobb__hair_layout *l)
{
    uint64_t at = HAIROBB__HAIR_HEADER;
    if (memcmp(header, "HAIR", 4) != 0) return HAIROBB_ERROR_INVALID_FILE;
    l->strands = hairobb__le_u32(header + 4);
    l->points = hairobb__le_u32(header + 8);
    l->flags = hairobb__le_u32(header + 12);
    l->default_segments = hairobb__le_u32(header + 16);
    /* reserved bits set, or no points: not a file this reader understands */
    if ((l->flags & ~31u) != 0 || !(l->flags & HAIROBB__HAIR_POINTS)) return HAIROBB_ERROR_INVALID_FILE;
    l->segments_at = at;
    if (l->flags & HAIROBB__HAIR_SEGMENTS) at += 2 * (uint64_t)l->strands;
    l->points_at = at;
    at += 12 * (uint64_t)l->points;
    l->thickness_at = at;
    if (l->flags & HAIROBB__HAIR_THICKNESS) at += 4 * (uint64_t)l->points;
    l->transparency_at = at;
    if (l->flags & HAIROBB__HAIR_TRANSPARENCY) at += 4 * (uint64_t)l->points;
    l->colors_at = at;
    if (l->flags & HAIROBB__HAIR_COLORS) at += 12 * (uint64_t)l->points;
    l->size = at;
    return HAIROBB_OK;
}

static uint64_t hairobb__strand_length(const unsigned char *data, const hairobb__hair_layout *l, uint32_t strand)
{
    const unsigned char *p = data + l->segments_at + 2 * (uint64_t)strand;
    uint64_t segments = (l->flags & HAIROBB__HAIR_SEGMENTS) ? (uint64_t)(p[0] | p[1] << 8) : (uint64_t)l->default_segments;
    return segments + 1;
}

/* One block holds every array; its size for the counts, or 0 if it would
   not fit a size_t. */
static size_t hairobb__hair_block_size(const hairobb__hair_layout *l, uint64_t vertices, uint64_t segments)
{
    uint64_t bytes = 16 * vertices + 32 + 8 * segments + 4 * (uint64_t)l->strands + 16 * (uint64_t)l->points;
    if (l->flags & HAIROBB__HAIR_TRANSPARENCY) bytes += 4 * (uint64_t)l->points;
    if (l->flags & HAIROBB__HAIR_COLORS) bytes += 12 * (uint64_t)l->points;
    return bytes <= (uint64_t)((size_t)-1) ? (size_t)bytes : 0;
}

/* Reads point i (radius = half the thickness); 0 if it is not finite, too
   large, or thinner than nothing. */
static int hairobb__hair_point(const unsigned char *data, const hairobb__hair_layout *l, float default_thickness,
                               size_t i, float point[4])
{
    int c;
    float thickness = (l->flags & HAIROBB__HAIR_THICKNESS) ? hairobb__le_float(data + l->thickness_at + 4 * (uint64_t)i)
                                                           : default_thickness;
    for (c = 0; c < 3; ++c) point[c] = hairobb__le_float(data + l->points_at + 12 * (uint64_t)i + 4 * (uint64_t)c);
    point[3] = 0.5f * thickness;
    for (c = 0; c < 4; ++c)
        if (!(fabsf(point[c]) <= HAIROBB__MAX_COORD)) return 0;
    return point[3] >= 0.0f;
}

/* Copies count floats (little-endian bytes at `at`); 0 if one is not finite. */
static int hairobb__hair_floats(const unsigned char *data, uint64_t at, size_t count, float *out)
{
    size_t i;
    for (i = 0; i < count; ++i) {
        out[i] = hairobb__le_float(data + at + 4 * (uint64_t)i);
        if (!(fabsf(out[i]) <= FLT_MAX)) return 0;
    }
    return 1;
}

/* A strand's points p[0..n-1] as n-1 Bezier segments of the uniform
   Catmull-Rom spline through them (p[-1] = p[0], p[n] = p[n-1]): each
   segment interpolates its two points, tangents match at the joints. Radii
   are clamped at 0, so r(u) >= 0 (a Bezier of non-negative radii). */
static void hairobb__catmull_rom_strand(const float *p, size_t n, float *vertices)
{
    size_t i;
    for (i = 0; i + 1 < n; ++i) {
        float around[16], bezier[16];
        memcpy(around, p + 4 * (i > 0 ? i - 1 : 0), 4 * sizeof(float));
        memcpy(around + 4, p + 4 * i, 8 * sizeof(float));
        memcpy(around + 12, p + 4 * (i + 2 < n ? i + 2 : n - 1), 4 * sizeof(float));
        hairobb__to_bezier(HAIROBB_BASIS_CATMULL_ROM, around, NULL, bezier);
        memcpy(vertices + 12 * i, bezier, 12 * sizeof(float));   /* the end point is the next one's start */
    }
    memcpy(vertices + 12 * (n - 1), p + 4 * (n - 1), 4 * sizeof(float));
}

HAIROBB_DEF hairobb_result hairobb_hair_read(const void *data, size_t size, void *allocator_user, hairobb_hair *hair)
{
    const unsigned char *bytes = HAIROBB__CAST(const unsigned char *, data);
    hairobb__hair_layout l;
    hairobb_result result;
    uint64_t points_in_strands = 0, vertex_count = 0, segment_count = 0;
    size_t block_size, point = 0, vertex = 0, segment = 0, i;
    unsigned char *block;
    float default_thickness;
    uint32_t k;

    if (!hair) return HAIROBB_ERROR_INVALID_ARGUMENT;
    memset(hair, 0, sizeof *hair);
    if (!data) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (size < HAIROBB__HAIR_HEADER) return HAIROBB_ERROR_INVALID_FILE;
    result = hairobb__hair_layout_of(bytes, &l);
    if (result != HAIROBB_OK) return result;
    if (l.size != (uint64_t)size) return HAIROBB_ERROR_INVALID_FILE;   /* truncated, or more than announced */

    /* the strands' points must add up to the point count; without a
       segments array that is one product, so a lying strand count costs
       no loop */
    if (!(l.flags & HAIROBB__HAIR_SEGMENTS) && (uint64_t)l.strands * ((uint64_t)l.default_segments + 1) != l.points)
        return HAIROBB_ERROR_INVALID_FILE;
    for (k = 0; k < l.strands; ++k) {
        uint64_t n = hairobb__strand_length(bytes, &l, k);
        points_in_strands += n;
        if (points_in_strands > l.points) return HAIROBB_ERROR_INVALID_FILE;
        if (n >= 2) {
            segment_count += n - 1;
            vertex_count += 3 * (n - 1) + 1;
        }
    }
    if (points_in_strands != l.points) return HAIROBB_ERROR_INVALID_FILE;
    if (vertex_count > 0xffffffffu) return HAIROBB_ERROR_TOO_LARGE;   /* indices are 32 bits */
    block_size = hairobb__hair_block_size(&l, vertex_count, segment_count);
    if (block_size == 0) return HAIROBB_ERROR_TOO_LARGE;

    block = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(block_size, allocator_user));
    if (!block) return HAIROBB_ERROR_OUT_OF_MEMORY;
    hair->allocation = block;
    hair->allocator_user = allocator_user;
    /* float4 arrays first, 16-byte aligned; Embree may read 16 bytes past the
       last vertex */
    hair->vertices = HAIROBB__CAST(float *, HAIROBB__CAST(void *, block + ((16 - ((uintptr_t)block & 15)) & 15)));
    hair->points = hair->vertices + 4 * vertex_count + 4;
    hair->colors = (l.flags & HAIROBB__HAIR_COLORS) ? hair->points + 4 * (size_t)l.points : NULL;
    hair->transparency = (l.flags & HAIROBB__HAIR_TRANSPARENCY)
                             ? hair->points + (hair->colors ? 7 : 4) * (size_t)l.points : NULL;
    hair->strand_points = HAIROBB__CAST(uint32_t *, HAIROBB__CAST(void *, hair->points + 4 * (size_t)l.points +
                              (hair->colors ? 3 * (size_t)l.points : 0) + (hair->transparency ? (size_t)l.points : 0)));
    hair->indices = hair->strand_points + l.strands;
    hair->segment_point = hair->indices + segment_count;
    hair->vertex_count = (size_t)vertex_count;
    hair->segment_count = (size_t)segment_count;
    hair->strand_count = l.strands;
    hair->point_count = l.points;
    hair->default_transparency = hairobb__le_float(bytes + 24);
    for (k = 0; k < 3; ++k) hair->default_color[k] = hairobb__le_float(bytes + 28 + 4 * k);
    memcpy(hair->info, bytes + 40, 88);
    hair->info[88] = '\0';

    default_thickness = hairobb__le_float(bytes + 20);
    result = HAIROBB_ERROR_INVALID_GEOMETRY;
    for (i = 0; i < l.points; ++i)
        if (!hairobb__hair_point(bytes, &l, default_thickness, i, hair->points + 4 * i)) goto failed;
    result = HAIROBB_ERROR_INVALID_FILE;
    if (hair->transparency && !hairobb__hair_floats(bytes, l.transparency_at, l.points, hair->transparency)) goto failed;
    if (hair->colors && !hairobb__hair_floats(bytes, l.colors_at, 3 * (size_t)l.points, hair->colors)) goto failed;

    for (k = 0; k < l.strands; ++k) {
        size_t n = (size_t)hairobb__strand_length(bytes, &l, k);
        hair->strand_points[k] = (uint32_t)n;
        if (n >= 2) {
            hairobb__catmull_rom_strand(hair->points + 4 * point, n, hair->vertices + 4 * vertex);
            for (i = 0; i + 1 < n; ++i, ++segment) {
                hair->indices[segment] = (uint32_t)(vertex + 3 * i);
                hair->segment_point[segment] = (uint32_t)(point + i);
            }
            vertex += 3 * (n - 1) + 1;
        }
        point += n;
    }
    memset(hair->vertices + 4 * vertex_count, 0, 4 * sizeof(float));   /* the padding */
    return HAIROBB_OK;

failed:
    hairobb_hair_free(hair);
    return result;
}

#ifndef HAIROBB_NO_STDIO
/* A file's length in bytes, the file left at its start; 0 where it cannot
   be told. Windows' long has 32 bits: its 64-bit calls there, so that
   files past 2 GB load. */
static int hairobb__file_length(FILE *file, uint64_t *length)
{
#if defined(_WIN32)
    __int64 end;
    if (_fseeki64(file, 0, SEEK_END) != 0 || (end = _ftelli64(file)) < 0 || _fseeki64(file, 0, SEEK_SET) != 0) return 0;
#else
    long end;
    if (fseek(file, 0, SEEK_END) != 0 || (end = ftell(file)) < 0 || fseek(file, 0, SEEK_SET) != 0) return 0;
#endif
    *length = (uint64_t)end;
    return 1;
}

/* The header first, so that a file of another size is an error before
   anything of its announced size is allocated. */
HAIROBB_DEF hairobb_result hairobb_hair_load(const char *path, void *allocator_user, hairobb_hair *hair)
{
    unsigned char header[HAIROBB__HAIR_HEADER], *data;
    hairobb__hair_layout l;
    hairobb_result result;
    FILE *file;
    uint64_t length;
    if (!hair) return HAIROBB_ERROR_INVALID_ARGUMENT;
    memset(hair, 0, sizeof *hair);
    if (!path) return HAIROBB_ERROR_INVALID_ARGUMENT;
    file = fopen(path, "rb");
    if (!file) return HAIROBB_ERROR_IO;
    if (fread(header, 1, sizeof header, file) != sizeof header)
        result = ferror(file) ? HAIROBB_ERROR_IO : HAIROBB_ERROR_INVALID_FILE;   /* a directory, or too short */
    else
        result = hairobb__hair_layout_of(header, &l);
    if (result == HAIROBB_OK && !hairobb__file_length(file, &length))
        result = HAIROBB_ERROR_IO;
    else if (result == HAIROBB_OK && length != l.size)
        result = HAIROBB_ERROR_INVALID_FILE;
    else if (result == HAIROBB_OK && l.size > (uint64_t)((size_t)-1))
        result = HAIROBB_ERROR_TOO_LARGE;
    if (result == HAIROBB_OK) {
        data = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC((size_t)l.size, allocator_user));
        if (!data)
            result = HAIROBB_ERROR_OUT_OF_MEMORY;
        else if (fread(data, 1, (size_t)l.size, file) != (size_t)l.size)
            result = HAIROBB_ERROR_IO;
        else
            result = hairobb_hair_read(data, (size_t)l.size, allocator_user, hair);
        if (data) HAIROBB_FREE(data, allocator_user);
    }
    fclose(file);
    return result;
}
#endif

HAIROBB_DEF void hairobb_hair_free(hairobb_hair *hair)
{
    if (!hair) return;
    if (hair->allocation) HAIROBB_FREE(hair->allocation, hair->allocator_user);
    memset(hair, 0, sizeof *hair);
}

/* ------------------------------------------------------------------------ */
/* >>hair_space  Hair space: references, the builder, frames                */
/* ------------------------------------------------------------------------ */
/* A reference is a segment, or the part [u0, u1] of one that spatial splits
   clipped. The builder keeps them in arrays indexed by position; a range of
   positions [begin, end) owns the slack [end, cap) that its spatial splits
   may fill with the extra references they create. */
typedef struct hairobb__range {
    size_t begin, end, cap;
} hairobb__range;

/* heuristics a subtree still tries (see hairobb__update_tries) */
#define HAIROBB__TRY_HAIR_SPACE 1u
#define HAIROBB__TRY_SPATIAL 2u
#define HAIROBB__TRY_CLUSTER 4u
#ifndef HAIROBB__STRIKES
#define HAIROBB__STRIKES 3      /* see hairobb__update_tries */
#endif
typedef struct hairobb__tries {
    unsigned enabled;
    unsigned char losses[3];    /* splits lost in a row, per heuristic bit */
} hairobb__tries;

typedef struct hairobb__builder {
    const float *vertices;
    const uint32_t *indices;
    hairobb_basis basis;              /* of vertices and indices (Bezier, or read without the copy) */
    const float *tangents;
    unsigned time_steps;              /* motion blur: >= 2 steps (vertices = the first), else 0 */
    const float *const *time_vertices;
    int sah_mid_time;                 /* moving nodes (linear bounds): the SAH's boxes are at mid-time */
    uint32_t *ids;                    /* segment of each position */
    float *ranges;                    /* u0, u1 per position; NULL without spatial splits: all [0, 1] */
    float *world_boxes;               /* 6 per position: lower, upper */
    /* 6 per position of the range being split (from frame_first on): its
       boxes in the frame last binned; room for frame_capacity positions,
       what the ranges binned in a frame span (hairobb__frame_capacity) */
    float *frame_boxes;
    size_t frame_first, frame_capacity;
    size_t capacity;                  /* positions */
    unsigned char *node_allocation, *nodes;
    size_t node_bytes, node_capacity;
    size_t node_reserve;              /* the first block's bytes (a task's guess from its size) */
    void *user;
    hairobb_node_policy policy;
    hairobb_obb_layout obb_layout;
    unsigned max_leaf, candidates;
    hairobb_progress_fn progress;
    void *progress_user;
    size_t positions_done;
    size_t top_done, top_work;        /* references the top's splits binned, and an estimate of their sum */
    float next_report;                /* the fraction that makes the next progress call */
    hairobb_stats stats;
    hairobb_result error;             /* first failure; the build unwinds */
    const uint32_t *segment_of;       /* in a task with its own copy of the points: each local id's segment */
    size_t task_limit;                /* ranges this small become tasks (0: none, or inside one) */
    struct hairobb__task *tasks;
    size_t task_count, task_capacity;
    struct hairobb__pool *pool;       /* the top's: threads that run its tasks while it adds them; else NULL */
} hairobb__builder;

/* A subtree the top of the tree left to be built on its own, in its own
   node memory, by any thread; the tasks depend on the input size only, so
   every thread count builds the same tree. */
typedef struct hairobb__task {
    hairobb__range range;
    unsigned depth;
    hairobb__tries tries;
    uint64_t root;                    /* in the task's node memory */
    unsigned char *node_allocation, *nodes;
    size_t node_bytes, node_delta;    /* node_delta: where its nodes went in the final memory */
    hairobb_stats stats;
    hairobb_result error;
    int ran;                          /* a user's parallel_for must run each task */
    unsigned char *slot;              /* where the tree names it (the last pass's) */
    size_t leaf_first;                /* its leaves' first id in the BVH's leaf ids */
    int finished;                     /* the last pass's part ran */
} hairobb__task;

/* Control points (x, y, z, r each) of the part [u0, u1] of a segment cp
   that spatial splits clipped, computed in double from the blossom of the
   segment so the float hull still holds the curve. */
static const float *hairobb__clipped_points(const float *cp, double u0, double u1, float scratch[16])
{
    int point, k;
    for (point = 0; point < 4; ++point) {
        /* blossom B(t1, t2, t3) with the t's u0 or u1: point 0 = (u0,u0,u0), 3 = (u1,u1,u1) */
        double t[3];
        t[0] = point >= 3 ? u1 : u0;
        t[1] = point >= 2 ? u1 : u0;
        t[2] = point >= 1 ? u1 : u0;
        for (k = 0; k < 4; ++k) {
            double c[4];
            int level, j;
            for (j = 0; j < 4; ++j) c[j] = cp[4 * j + k];
            for (level = 0; level < 3; ++level)
                for (j = 0; j < 3 - level; ++j) c[j] = (1.0 - t[level]) * c[j] + t[level] * c[j + 1];
            scratch[4 * point + k] = (float)c[0];
        }
    }
    return scratch;
}

/* The Bezier control points of segment id as the builder reads it from
   vertices (b->vertices, or a motion step's). */
HAIROBB__INLINE const float *hairobb__builder_points(const hairobb__builder *b, const float *vertices, uint32_t id,
                                                     float scratch[16])
{
    size_t at = 4 * (size_t)b->indices[id];
    if (b->basis == HAIROBB_BASIS_BEZIER) return vertices + at;
    hairobb__to_bezier(b->basis, vertices + at, b->tangents ? b->tangents + at : NULL, scratch);
    return scratch;
}

/* Asks the cache for what hairobb__builder_points will read for position
   i + HAIROBB__AHEAD (its segment's points) and i + 2 HAIROBB__AHEAD (its
   index), while the loop works on position i: passes over large ranges read
   segments in no order of memory. Positions past `end` are not touched. */
#define HAIROBB__AHEAD 8
HAIROBB__INLINE void hairobb__prefetch_points(const hairobb__builder *b, size_t i, size_t end)
{
    if (i + 2 * HAIROBB__AHEAD < end) HAIROBB__PREFETCH(b->indices + b->ids[i + 2 * HAIROBB__AHEAD]);
    if (i + HAIROBB__AHEAD < end) HAIROBB__PREFETCH(b->vertices + 4 * (size_t)b->indices[b->ids[i + HAIROBB__AHEAD]]);
}

/* Control points of the reference at position i: the caller's, or its
   clipped part's. Inline: most references are whole segments, and every
   box pass asks. */
HAIROBB__INLINE const float *hairobb__ref_points_in(const hairobb__builder *b, const float *vertices, size_t i, float scratch[16])
{
    static const float whole[2] = {0.0f, 1.0f};
    float converted[16];
    const float *cp = hairobb__builder_points(b, vertices, b->ids[i], converted);
    /* the bits of [0, 1]: u0 is +0 or above (set_range's 0, or a clip strictly inside);
       no ranges (a refit of a tree without clipped references): all whole */
    if (!b->ranges || memcmp(b->ranges + 2 * i, whole, sizeof whole) == 0) {
        if (cp == converted) { memcpy(scratch, converted, sizeof converted); return scratch; }
        return cp;
    }
    return hairobb__clipped_points(cp, b->ranges[2 * i], b->ranges[2 * i + 1], scratch);
}

HAIROBB__INLINE const float *hairobb__ref_points(const hairobb__builder *b, size_t i, float scratch[16])
{
    return hairobb__ref_points_in(b, b->vertices, i, scratch);
}

/* The other steps of a moving reference grown into its box (of step 0):
   the control points lerped at any time lie in the hull of the two steps'
   (a clipped part's too: clipping is linear in the points) and a lerped
   radius is at most the larger, so the union of the steps' boxes bounds
   the ribbon at every time. */
static void hairobb__ref_box_steps(const hairobb__builder *b, size_t i, const hairobb__frame_prep *f, const float *centre,
                                   const float *row_norms, hairobb__b4 *lower, hairobb__b4 *upper)
{
    unsigned step;
    for (step = 1; step < b->time_steps; ++step) {
        float scratch[16];
        hairobb__b4 lo, hi;
        hairobb__segment_box_v4(hairobb__ref_points_in(b, b->time_vertices[step], i, scratch), f, centre, row_norms, &lo, &hi);
        *lower = hairobb__b4_min(*lower, lo);
        *upper = hairobb__b4_max(*upper, hi);
    }
}

/* The box of a moving reference over every step: its union. */
static void hairobb__ref_box_union(const hairobb__builder *b, size_t i, const hairobb__frame_prep *f, const float *centre,
                                   const float *row_norms, hairobb__b4 *lower, hairobb__b4 *upper)
{
    float scratch[16];
    hairobb__segment_box_v4(hairobb__ref_points(b, i, scratch), f, centre, row_norms, lower, upper);
    hairobb__ref_box_steps(b, i, f, centre, row_norms, lower, upper);
}

/* The box of a moving reference: over every step (the union), or at
   mid-time (the middle step, or halfway between the two around it) for
   the SAH where nodes store linear bounds, whose boxes follow the hair at
   each time, so that their area is about the box at one time, not the
   sweep's (then never a bound). */
static void hairobb__ref_box_moving(const hairobb__builder *b, size_t i, const hairobb__frame_prep *f, const float *centre,
                                    const float *row_norms, hairobb__b4 *lower, hairobb__b4 *upper)
{
    unsigned k = (b->time_steps - 1) / 2;
    float first[16], second[16], mid[16];
    const float *p;
    if (!b->sah_mid_time) {
        hairobb__ref_box_union(b, i, f, centre, row_norms, lower, upper);
        return;
    }
    p = hairobb__ref_points_in(b, b->time_vertices[k], i, first);
    if (b->time_steps % 2 == 0) {
        const float *q = hairobb__ref_points_in(b, b->time_vertices[k + 1], i, second);
        int j;
        for (j = 0; j < 16; ++j) mid[j] = 0.5f * p[j] + 0.5f * q[j];
        p = mid;
    }
    hairobb__segment_box_v4(p, f, centre, row_norms, lower, upper);
}

/* Box of the reference at position i in frame f (hairobb__segment_box_v4's
   arguments), over every time step of moving hair, or at mid-time for the
   SAH of linear bounds (sah_mid_time): every box the builder and the refit
   compute comes from here, but a moving node's (hairobb__node_box_ends). */
HAIROBB__INLINE void hairobb__ref_box_v4(const hairobb__builder *b, size_t i, const hairobb__frame_prep *f, const float *centre,
                                         const float *row_norms, hairobb__b4 *lower, hairobb__b4 *upper)
{
    float scratch[16];
    if (b->time_steps) {
        hairobb__ref_box_moving(b, i, f, centre, row_norms, lower, upper);
        return;
    }
    hairobb__segment_box_v4(hairobb__ref_points(b, i, scratch), f, centre, row_norms, lower, upper);
}

HAIROBB__INLINE void hairobb__ref_box(const hairobb__builder *b, size_t i, const hairobb__frame_prep *f, const float *centre,
                                      const float *row_norms, float lower[3], float upper[3])
{
    hairobb__b4 lo, hi;
    hairobb__ref_box_v4(b, i, f, centre, row_norms, &lo, &hi);
    hairobb__b4_store3(lower, lo);
    hairobb__b4_store3(upper, hi);
}

static void hairobb__prim_box(const hairobb__builder *b, size_t i, const hairobb__frame_prep *frame,
                              float lower[3], float upper[3])
{
    if (!frame) {
        memcpy(lower, b->world_boxes + 6 * i, 3 * sizeof(float));
        memcpy(upper, b->world_boxes + 6 * i + 3, 3 * sizeof(float));
    } else {
        hairobb__ref_box(b, i, frame, NULL, NULL, lower, upper);
    }
}

/* Unit main direction (first to last control point) of the reference at
   position i; 0 if it has none. */
static int hairobb__ref_direction(const hairobb__builder *b, size_t i, float d[3])
{
    float scratch[16], len;
    const float *cp = hairobb__ref_points(b, i, scratch);
    d[0] = cp[12] - cp[0]; d[1] = cp[13] - cp[1]; d[2] = cp[14] - cp[2];
    len = sqrtf(hairobb__dot3(d, d));
    if (!(len > 0.0f) || !(len < FLT_MAX)) return 0;
    d[0] /= len; d[1] /= len; d[2] /= len;
    return 1;
}

/* The position of the k-th reference of a list of ranges. */
static size_t hairobb__position_at(const hairobb__range *ranges, size_t k)
{
    while (k >= ranges->end - ranges->begin) { k -= ranges->end - ranges->begin; ++ranges; }
    return ranges->begin + k;
}

/* Picks, among the main directions of evenly spaced references of the
   ranges (and the world axes when allow_identity), the rotation with the
   smallest summed surface area of the boxes of up to HAIROBB__SAMPLE evenly
   spaced references. Deterministic. Every candidate's sum in one pass over
   the samples: a sum the first candidates' best would have cut short (its
   partial sum already at least that best) loses either way, as sums only
   grow; the world axes' sum stops at FLT_MAX, as its cut-off was.
   candidate_frame, if given, gets the answer allow_identity = 0 gives (the
   same sums), for the range's own split next (hairobb__find_split). */
static void hairobb__choose_hair_spaces(const hairobb__builder *b, const hairobb__range *ranges, int range_count,
                                        int allow_identity, float best_frame[9], float *candidate_frame)
{
    size_t count = 0, step, k;
    unsigned c, candidates, n = 0;
    float frames[HAIROBB__MAX_CANDIDATES][9], areas[HAIROBB__MAX_CANDIDATES], world_area = 0.0f, best_area;
    hairobb__frame_prep preps[HAIROBB__MAX_CANDIDATES];
    int i, best = -1;
    for (i = 0; i < range_count; ++i) count += ranges[i].end - ranges[i].begin;
    candidates = b->candidates < count ? b->candidates : (unsigned)count;
    for (c = 0; c < candidates; ++c) {
        float d[3];
        size_t pick = hairobb__position_at(ranges, (count * (2 * c + 1)) / (2 * candidates));
        if (!hairobb__ref_direction(b, pick, d)) continue;
        hairobb__frame_from_direction(d, frames[n]);
        hairobb__prepare_frame(frames[n], &preps[n]);
        areas[n++] = 0.0f;
    }
    step = count > HAIROBB__SAMPLE ? count / HAIROBB__SAMPLE : 1;
    for (k = 0; k < count; k += step) {
        size_t at = hairobb__position_at(ranges, k);
        float scratch[16];
        const float *cp = hairobb__ref_points(b, at, scratch);
        if (allow_identity && world_area < FLT_MAX)
            world_area += hairobb__half_area(b->world_boxes + 6 * at, b->world_boxes + 6 * at + 3);
        for (c = 0; c < n; ++c) {
            hairobb__b4 lower, upper;
            hairobb__segment_box_v4(cp, &preps[c], NULL, NULL, &lower, &upper);
            areas[c] += hairobb__b4_half_area(lower, upper);
        }
    }
    /* the first cheapest candidate; it beats the world axes only if cheaper */
    best_area = FLT_MAX;
    for (c = 0; c < n; ++c)
        if (areas[c] < best_area) { best_area = areas[c]; best = (int)c; }
    if (candidate_frame) {
        if (best >= 0) memcpy(candidate_frame, frames[best], sizeof frames[best]);
        else hairobb__identity_frame(candidate_frame);
    }
    if (best >= 0 && (!allow_identity || best_area < world_area)) memcpy(best_frame, frames[best], sizeof frames[best]);
    else hairobb__identity_frame(best_frame);
}

static void hairobb__choose_hair_space(const hairobb__builder *b, const hairobb__range *ranges, int range_count,
                                       int allow_identity, float best_frame[9])
{
    hairobb__choose_hair_spaces(b, ranges, range_count, allow_identity, best_frame, NULL);
}

/* ------------------------------------------------------------------------ */
/* >>bins  Builder: binning (object bins, world and hair space, in parts)   */
/* ------------------------------------------------------------------------ */
enum { HAIROBB__SPLIT_MEDIAN, HAIROBB__SPLIT_OBJECT, HAIROBB__SPLIT_SPATIAL, HAIROBB__SPLIT_CLUSTER };

typedef struct hairobb__split {
    float cost;                 /* FLT_MAX: no split found */
    int kind;                   /* HAIROBB__SPLIT_* */
    unsigned heuristic;         /* HAIROBB__TRY_* bits of what won; 0 world object binning */
    int hair_space;             /* the split was made in frame, not world axes */
    float frame[9];
    int axis;
    float bin_origin, bin_scale;
    int last_left_bin;          /* bins 0..last_left_bin go left */
    float direction[2][3];      /* clusters: the two main directions */
    float area_left, area_right;
    float parent_area;          /* world box of the range being split */
} hairobb__split;


/* Bins per unit of an extent, just under bins / extent so that the upper
   end falls in the last bin; 0 (do not bin) for extents so small that the
   scale would overflow (subnormal input found by the .hair fuzzer). */
static float hairobb__bin_scale(int bins, float extent)
{
    return extent >= (float)HAIROBB__BINS * FLT_MIN ? (float)bins * (1.0f - 1.0f / 1024.0f) / extent : 0.0f;
}

/* The box (lower, upper) in the frame last binned of the reference at
   position i of the range being split (hairobb__find_split). */
HAIROBB__INLINE float *hairobb__frame_box(const hairobb__builder *b, size_t i)
{
    return b->frame_boxes + 6 * (i - b->frame_first);
}

/* Box of the reference at position i: its world box, or (frame given)
   the box hairobb__bin_split computed in that frame. */
static void hairobb__box_at(const hairobb__builder *b, const float *frame, size_t i, float lower[3], float upper[3])
{
    const float *box = frame ? hairobb__frame_box(b, i) : b->world_boxes + 6 * i;
    memcpy(lower, box, 3 * sizeof(float));
    memcpy(upper, box + 3, 3 * sizeof(float));
}

/* The plane after bin `bin` of a sweep is the best split so far. */
static void hairobb__take_split(hairobb__split *best, float cost, int kind, const float *frame, int axis, float origin,
                                float scale, int bin, float left_area, float right_area)
{
    best->cost = cost;
    best->kind = kind;
    best->hair_space = frame != NULL;
    best->heuristic = (frame ? HAIROBB__TRY_HAIR_SPACE : 0u) | (kind == HAIROBB__SPLIT_SPATIAL ? HAIROBB__TRY_SPATIAL : 0u);
    if (frame) memcpy(best->frame, frame, sizeof best->frame);
    best->axis = axis;
    best->bin_origin = origin;
    best->bin_scale = scale;
    best->last_left_bin = bin;
    best->area_left = left_area;
    best->area_right = right_area;
}

/* One sweep over binned boxes: counts[bin] enter from the left (entries) and
   leave to the right (exits); for object bins both are the bin's count.
   Keeps the cheapest plane in *best. */
static void hairobb__sweep_bins(int bins, const float bin_lower[][3], const float bin_upper[][3], const size_t *entries,
                                const size_t *exits, float box_cost, int kind, const float *frame, int axis,
                                float origin, float scale, hairobb__split *best)
{
    float right_area[HAIROBB__BINS], lo[3], hi[3];
    size_t right_count[HAIROBB__BINS], left_count = 0;
    int bin;
    hairobb__box_empty(lo, hi);
    for (bin = bins - 1; bin > 0; --bin) {
        hairobb__box_grow(lo, hi, bin_lower[bin], bin_upper[bin]);
        right_count[bin] = exits[bin] + (bin + 1 < bins ? right_count[bin + 1] : 0);
        right_area[bin] = right_count[bin] ? hairobb__half_area(lo, hi) : 0.0f;
    }
    hairobb__box_empty(lo, hi);
    for (bin = 0; bin < bins - 1; ++bin) {
        float cost, left_area;
        hairobb__box_grow(lo, hi, bin_lower[bin], bin_upper[bin]);
        left_count += entries[bin];
        if (left_count == 0 || right_count[bin + 1] == 0) continue;
        left_area = hairobb__half_area(lo, hi);
        cost = box_cost + HAIROBB__COST_SEGMENT * (left_area * (float)left_count + right_area[bin + 1] * (float)right_count[bin + 1]);
        if (cost < best->cost) hairobb__take_split(best, cost, kind, frame, axis, origin, scale, bin, left_area, right_area[bin + 1]);
    }
}

#if HAIROBB__SSE
/* (dx dy + dy dz) + dz dx of boxes with one axis per vector (lanes: boxes) */
HAIROBB__INLINE __m128 hairobb__half_areas(const __m128 lower[3], const __m128 upper[3])
{
    __m128 dx = _mm_sub_ps(upper[0], lower[0]), dy = _mm_sub_ps(upper[1], lower[1]), dz = _mm_sub_ps(upper[2], lower[2]);
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dy), _mm_mul_ps(dy, dz)), _mm_mul_ps(dz, dx));
}

/* The three axes' object sweeps (hairobb__sweep_bins) at once, lane = axis (bins
   transposed): the same floats. Each lane keeps its first cheapest plane,
   then the axes in order beat *best or not, as one sweep after the other
   would have left it. Counts below 2^31 (int lanes). */
static void hairobb__sweep_objects(int bins, const hairobb__b4 (*bin_lower)[HAIROBB__BINS],
                                   const hairobb__b4 (*bin_upper)[HAIROBB__BINS], const uint32_t (*count)[4],
                                   float box_cost, const float *frame, const float origin[3], const float scale[3],
                                   hairobb__split *best)
{
    __m128 box[HAIROBB__BINS][6], right_area[HAIROBB__BINS], lo[3], hi[3];
    __m128 best_cost = _mm_set1_ps(INFINITY), best_left = _mm_setzero_ps(), best_right = _mm_setzero_ps();
    __m128i right_count[HAIROBB__BINS + 1], zero = _mm_setzero_si128(), left_count = zero, best_bin = zero;
    float costs[4], lefts[4], rights[4];
    int bin, k, bins_at[4];
    for (bin = 0; bin < bins; ++bin) {
        __m128 l0 = bin_lower[0][bin], l1 = bin_lower[1][bin], l2 = bin_lower[2][bin], l3 = l2;
        __m128 u0 = bin_upper[0][bin], u1 = bin_upper[1][bin], u2 = bin_upper[2][bin], u3 = u2;
        _MM_TRANSPOSE4_PS(l0, l1, l2, l3);
        _MM_TRANSPOSE4_PS(u0, u1, u2, u3);
        box[bin][0] = l0; box[bin][1] = l1; box[bin][2] = l2;
        box[bin][3] = u0; box[bin][4] = u1; box[bin][5] = u2;
    }
    /* written out: gcc -O2 kept a loop over k here */
#define HAIROBB__GROW_AXES(bin) \
        lo[0] = _mm_min_ps(lo[0], box[bin][0]); hi[0] = _mm_max_ps(hi[0], box[bin][3]); \
        lo[1] = _mm_min_ps(lo[1], box[bin][1]); hi[1] = _mm_max_ps(hi[1], box[bin][4]); \
        lo[2] = _mm_min_ps(lo[2], box[bin][2]); hi[2] = _mm_max_ps(hi[2], box[bin][5]);
    for (k = 0; k < 3; ++k) { lo[k] = _mm_set1_ps(FLT_MAX); hi[k] = _mm_set1_ps(-FLT_MAX); }
    right_count[bins] = zero;
    for (bin = bins - 1; bin > 0; --bin) {
        __m128i n;
        HAIROBB__GROW_AXES(bin)
        n = right_count[bin] = _mm_add_epi32(_mm_loadu_si128(HAIROBB__CAST(const __m128i *, HAIROBB__CAST(const void *, count[bin]))),
                                             right_count[bin + 1]);
        right_area[bin] = _mm_andnot_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(n, zero)), hairobb__half_areas(lo, hi));
    }
    for (k = 0; k < 3; ++k) { lo[k] = _mm_set1_ps(FLT_MAX); hi[k] = _mm_set1_ps(-FLT_MAX); }
    for (bin = 0; bin < bins - 1; ++bin) {
        __m128i n = right_count[bin + 1];
        __m128 empty, left_area, cost, take;
        HAIROBB__GROW_AXES(bin)
        left_count = _mm_add_epi32(left_count, _mm_loadu_si128(HAIROBB__CAST(const __m128i *, HAIROBB__CAST(const void *, count[bin]))));
        empty = _mm_castsi128_ps(_mm_or_si128(_mm_cmpeq_epi32(left_count, zero), _mm_cmpeq_epi32(n, zero)));
        left_area = hairobb__half_areas(lo, hi);
        cost = _mm_add_ps(_mm_set1_ps(box_cost),
                          _mm_mul_ps(_mm_set1_ps(HAIROBB__COST_SEGMENT),
                                     _mm_add_ps(_mm_mul_ps(left_area, _mm_cvtepi32_ps(left_count)),
                                                _mm_mul_ps(right_area[bin + 1], _mm_cvtepi32_ps(n)))));
        take = _mm_andnot_ps(empty, _mm_cmplt_ps(cost, best_cost));
        best_cost = _mm_or_ps(_mm_and_ps(take, cost), _mm_andnot_ps(take, best_cost));
        best_left = _mm_or_ps(_mm_and_ps(take, left_area), _mm_andnot_ps(take, best_left));
        best_right = _mm_or_ps(_mm_and_ps(take, right_area[bin + 1]), _mm_andnot_ps(take, best_right));
        best_bin = _mm_or_si128(_mm_and_si128(_mm_castps_si128(take), _mm_set1_epi32(bin)),
                                _mm_andnot_si128(_mm_castps_si128(take), best_bin));
    }
#undef HAIROBB__GROW_AXES
    _mm_storeu_ps(costs, best_cost);
    _mm_storeu_ps(lefts, best_left);
    _mm_storeu_ps(rights, best_right);
    _mm_storeu_si128(HAIROBB__CAST(__m128i *, HAIROBB__CAST(void *, bins_at)), best_bin);
    for (k = 0; k < 3; ++k)
        if (scale[k] > 0.0f && costs[k] < best->cost)
            hairobb__take_split(best, costs[k], HAIROBB__SPLIT_OBJECT, frame, k, origin[k], scale[k], bins_at[k], lefts[k], rights[k]);
}
#endif

/* Passes over every segment outside the tree's recursion (the world boxes
   first, the gather last) run in parts: at most HAIROBB__PARTS of at least
   HAIROBB__PART_MIN items, each part's results merged in part order, so
   any thread count gives the same bits. */
#define HAIROBB__PARTS 256
#define HAIROBB__PART_MIN 32768

static size_t hairobb__part_count(size_t items)
{
    size_t parts = items / HAIROBB__PART_MIN + 1;
    return parts > HAIROBB__PARTS ? HAIROBB__PARTS : parts;
}

/* Items [*begin, *end) of part k of `parts`. */
static void hairobb__part_items(size_t items, size_t parts, size_t k, size_t *begin, size_t *end)
{
    size_t each = items / parts + (items % parts != 0);
    *begin = k * each < items ? k * each : items;
    *end = *begin + each < items ? *begin + each : items;
}

/* What binning keeps of a range's boxes: their bounds and their centroids'
   (first pass), then each axis' bins (second pass). The passes over parts
   of a range merge, in part order, into the bits of one pass over it. */
typedef struct hairobb__box_bounds {
    hairobb__b4 centre_min, centre_max, lower, upper;
} hairobb__box_bounds;

typedef struct hairobb__object_bins {
    hairobb__b4 lower[3][HAIROBB__BINS], upper[3][HAIROBB__BINS];
    uint32_t count[HAIROBB__BINS][4];   /* [bin][axis]; a range holds at most 2^32-1 references */
} hairobb__object_bins;

HAIROBB__INLINE void hairobb__bounds_empty(hairobb__box_bounds *bounds)
{
    bounds->centre_min = bounds->lower = hairobb__b4_set1(FLT_MAX);
    bounds->centre_max = bounds->upper = hairobb__b4_set1(-FLT_MAX);
}

HAIROBB__INLINE void hairobb__bounds_grow(hairobb__box_bounds *bounds, hairobb__b4 lower, hairobb__b4 upper)
{
    hairobb__b4 c = hairobb__b4_mul(hairobb__b4_set1(0.5f), hairobb__b4_add(lower, upper));
    bounds->centre_min = hairobb__b4_min(bounds->centre_min, c);
    bounds->centre_max = hairobb__b4_max(bounds->centre_max, c);
    bounds->lower = hairobb__b4_min(bounds->lower, lower);
    bounds->upper = hairobb__b4_max(bounds->upper, upper);
}

/* The first pass over boxes already made (lower, upper: 6 floats each). */
HAIROBB__INLINE void hairobb__bound_boxes(const float *boxes, size_t count, hairobb__box_bounds *bounds)
{
    size_t i;
    hairobb__bounds_empty(bounds);
    for (i = 0; i < count; ++i) hairobb__bounds_grow(bounds, hairobb__b4_load4(boxes + 6 * i), hairobb__b4_load_upper(boxes + 6 * i));
}

HAIROBB__INLINE void hairobb__bounds_merge(hairobb__box_bounds *bounds, const hairobb__box_bounds *part)
{
    bounds->centre_min = hairobb__b4_min(bounds->centre_min, part->centre_min);
    bounds->centre_max = hairobb__b4_max(bounds->centre_max, part->centre_max);
    bounds->lower = hairobb__b4_min(bounds->lower, part->lower);
    bounds->upper = hairobb__b4_max(bounds->upper, part->upper);
}

/* The second pass: each box into the bin of its centroid on each axis. */
HAIROBB__INLINE void hairobb__bin_boxes(const float *boxes, size_t count, int bins, hairobb__b4 origin, hairobb__b4 scale,
                                        hairobb__object_bins *o)
{
    hairobb__b4 half = hairobb__b4_set1(0.5f);
    size_t i;
    int axis, bin;
    memset(o->count, 0, (size_t)bins * sizeof o->count[0]);
    for (axis = 0; axis < 3; ++axis)
        for (bin = 0; bin < bins; ++bin) {
            o->lower[axis][bin] = hairobb__b4_set1(FLT_MAX);
            o->upper[axis][bin] = hairobb__b4_set1(-FLT_MAX);
        }
    for (i = 0; i < count; ++i) {
        const float *box = boxes + 6 * i;
        hairobb__b4 lower = hairobb__b4_load4(box), upper = hairobb__b4_load_upper(box);
        int at[4];
        hairobb__b4_bins(hairobb__b4_mul(hairobb__b4_sub(hairobb__b4_mul(half, hairobb__b4_add(lower, upper)), origin), scale), at);
#define HAIROBB__BIN_INTO(axis) \
        o->lower[axis][at[axis]] = hairobb__b4_min(o->lower[axis][at[axis]], lower); \
        o->upper[axis][at[axis]] = hairobb__b4_max(o->upper[axis][at[axis]], upper); \
        o->count[at[axis]][axis]++;
        HAIROBB__BIN_INTO(0)
        HAIROBB__BIN_INTO(1)
        HAIROBB__BIN_INTO(2)
#undef HAIROBB__BIN_INTO
    }
}

static void hairobb__bins_merge(hairobb__object_bins *o, const hairobb__object_bins *part, int bins)
{
    int axis, bin;
    for (bin = 0; bin < bins; ++bin)
        for (axis = 0; axis < 3; ++axis) {
            o->lower[axis][bin] = hairobb__b4_min(o->lower[axis][bin], part->lower[axis][bin]);
            o->upper[axis][bin] = hairobb__b4_max(o->upper[axis][bin], part->upper[axis][bin]);
            o->count[bin][axis] += part->count[bin][axis];
        }
}

/* The top's large ranges are binned in world space in parts, by the
   calling thread and whichever pool threads are idle (hairobb__top_parts). */
#define HAIROBB__TOP_PARTS 16
#define HAIROBB__TOP_PART_MIN 65536

static void hairobb__top_parts(const hairobb__builder *b, size_t parts, hairobb_task_fn run, void *context);

/* Parts a range of the top is binned or boxed in; 0: one pass on the
   calling thread (no pool, or too few references). */
static size_t hairobb__top_part_count(const hairobb__builder *b, size_t count)
{
    if (!b->pool || count < 2 * HAIROBB__TOP_PART_MIN) return 0;
    return count / HAIROBB__TOP_PART_MIN < HAIROBB__TOP_PARTS ? count / HAIROBB__TOP_PART_MIN : HAIROBB__TOP_PARTS;
}

typedef struct hairobb__world_binning {
    const float *boxes;
    size_t count, parts;
    int bins;
    hairobb__b4 origin, scale;
    hairobb__box_bounds bounds[HAIROBB__TOP_PARTS];
    hairobb__object_bins binned[HAIROBB__TOP_PARTS];
} hairobb__world_binning;

static void hairobb__bound_part(void *context, unsigned k)
{
    hairobb__world_binning *w = HAIROBB__CAST(hairobb__world_binning *, context);
    size_t begin, end;
    hairobb__part_items(w->count, w->parts, k, &begin, &end);
    hairobb__bound_boxes(w->boxes + 6 * begin, end - begin, &w->bounds[k]);
}

static void hairobb__bin_part(void *context, unsigned k)
{
    hairobb__world_binning *w = HAIROBB__CAST(hairobb__world_binning *, context);
    size_t begin, end;
    hairobb__part_items(w->count, w->parts, k, &begin, &end);
    hairobb__bin_boxes(w->boxes + 6 * begin, end - begin, w->bins, w->origin, w->scale, &w->binned[k]);
}

/* The spatial split along one axis (of frame, NULL = world axes) of the
   range's box [bmin, bmax], taken into *best if it is cheaper and clips at
   most spatial_slack references. */
static void hairobb__spatial_bins(const hairobb__builder *b, const hairobb__range *r, const float *frame, int axis, int bins,
                                  const float bmin[3], const float bmax[3], float box_cost, size_t spatial_slack,
                                  hairobb__split *best)
{
    size_t i;
    float bin_lower[HAIROBB__BINS][3], bin_upper[HAIROBB__BINS][3];
    float scale = hairobb__bin_scale(bins, bmax[axis] - bmin[axis]);
    size_t bin_count[HAIROBB__BINS], exits[HAIROBB__BINS];
    int bin;
    if (scale > 0.0f) {
        /* each reference enters the bin of its lower end and leaves by that of
           its upper end; in between, its box clipped to each bin's slab is
           what it adds there (an upper bound of its clipped curve) */
        hairobb__split before = *best;
        for (bin = 0; bin < bins; ++bin) {
            hairobb__box_empty(bin_lower[bin], bin_upper[bin]);
            bin_count[bin] = exits[bin] = 0;
        }
        for (i = r->begin; i < r->end; ++i) {
            float lower[3], upper[3];
            int first, last;
            hairobb__box_at(b, frame, i, lower, upper);
            first = hairobb__bin_of(lower[axis], bmin[axis], scale);
            last = hairobb__bin_of(upper[axis], bmin[axis], scale);
            bin_count[first]++;
            exits[last]++;
            for (bin = first; bin <= last; ++bin) {
                float lo[3], hi[3];
                memcpy(lo, lower, sizeof lo);
                memcpy(hi, upper, sizeof hi);
                if (bin > first) lo[axis] = bmin[axis] + (float)bin / scale;
                if (bin < last) hi[axis] = bmin[axis] + (float)(bin + 1) / scale;
                hairobb__box_grow(bin_lower[bin], bin_upper[bin], lo, hi);
            }
        }
        hairobb__sweep_bins(bins, (const float (*)[3])bin_lower, (const float (*)[3])bin_upper, bin_count, exits,
                            box_cost, HAIROBB__SPLIT_SPATIAL, frame, axis, bmin[axis], scale, best);
        if (best->cost < before.cost) {
            /* the budget: count the references straddling the chosen plane */
            size_t straddling = 0;
            for (i = r->begin; i < r->end; ++i) {
                float lower[3], upper[3];
                hairobb__box_at(b, frame, i, lower, upper);
                if (hairobb__bin_of(lower[axis], bmin[axis], scale) <= best->last_left_bin &&
                    hairobb__bin_of(upper[axis], bmin[axis], scale) > best->last_left_bin) ++straddling;
            }
            if (straddling > spatial_slack) *best = before;   /* over budget: forget it */
        }
    }
}

/* Best SAH split of the range binned along the axes of frame (NULL = world
   axes): by centroid (object split) and, with spatial_slack > 0, by
   clipping references at the bin planes (spatial split) when at most
   spatial_slack of them straddle the plane. Costs are SAH costs times the
   parent's area *area: binning in world axes computes it (the half area of
   the range's world box, as hairobb__range_box gives), in a frame reads it;
   box_per_area times it is the cost of testing the two new child boxes. */
static void hairobb__bin_split(const hairobb__builder *b, const hairobb__range *r, const float *frame,
                               float box_per_area, float *area, size_t spatial_slack, hairobb__split *best)
{
    float box_cost;
    float bmin[3], bmax[3];
    /* boxes + 6 * (i - r->begin): position i's */
    float *boxes = frame ? hairobb__frame_box(b, r->begin) : b->world_boxes + 6 * r->begin;
    hairobb__box_bounds bounds;
    hairobb__world_binning *parted = NULL;
    hairobb__object_bins o;
    hairobb__frame_prep prep;
    size_t i, count = r->end - r->begin, parts = 0;
    /* fewer bins than references only wastes sweeps */
    int axis, bins = count < HAIROBB__BINS ? (int)count : HAIROBB__BINS;
    if (frame) {
        HAIROBB_ASSERT(b->frame_first == r->begin && count <= b->frame_capacity);
        hairobb__prepare_frame(frame, &prep);
        /* the boxes (computed here, for the binning and for
           hairobb__partition) and the bounds of their centroids, in one pass */
        hairobb__bounds_empty(&bounds);
        for (i = r->begin; i < r->end; ++i) {
            hairobb__b4 lower, upper;
            hairobb__prefetch_points(b, i, r->end);
            hairobb__ref_box_v4(b, i, &prep, NULL, NULL, &lower, &upper);
            hairobb__b4_store3(boxes + 6 * (i - r->begin), lower);
            hairobb__b4_store3(boxes + 6 * (i - r->begin) + 3, upper);
            hairobb__bounds_grow(&bounds, lower, upper);
        }
    } else if ((parts = hairobb__top_part_count(b, count)) > 1) {
        /* the top's world binning, in parts (the work area is large: not on the stack) */
        parted = HAIROBB__CAST(hairobb__world_binning *, HAIROBB_MALLOC(sizeof *parted, b->user));
    }
    if (parted) {
        size_t k;
        parted->boxes = boxes;
        parted->count = count;
        parted->parts = parts;
        parted->bins = bins;
        hairobb__top_parts(b, parted->parts, hairobb__bound_part, parted);
        bounds = parted->bounds[0];
        for (k = 1; k < parted->parts; ++k) hairobb__bounds_merge(&bounds, &parted->bounds[k]);
    } else if (!frame) {
        hairobb__bound_boxes(boxes, count, &bounds);
    }
    hairobb__b4_store3(bmin, bounds.lower);
    hairobb__b4_store3(bmax, bounds.upper);
    if (!frame) *area = hairobb__half_area(bmin, bmax);
    box_cost = box_per_area * *area;
    {
        /* object binning: one pass over the references for all three axes */
        float scales[3], origins[3];
        int bin;
        for (axis = 0; axis < 3; ++axis) {
            origins[axis] = hairobb__b4_lane(bounds.centre_min, axis);
            scales[axis] = hairobb__bin_scale(bins, hairobb__b4_lane(bounds.centre_max, axis) - origins[axis]);
        }
        if (parted) {
            size_t k;
            parted->origin = bounds.centre_min;
            parted->scale = hairobb__b4_set3(scales);
            hairobb__top_parts(b, parted->parts, hairobb__bin_part, parted);
            o = parted->binned[0];
            for (k = 1; k < parted->parts; ++k) hairobb__bins_merge(&o, &parted->binned[k], bins);
            HAIROBB_FREE(parted, b->user);
        } else {
            hairobb__bin_boxes(boxes, count, bins, bounds.centre_min, hairobb__b4_set3(scales), &o);
        }
#if HAIROBB__SSE
        if (count <= 0x7fffffffu) {
            hairobb__sweep_objects(bins, (const hairobb__b4 (*)[HAIROBB__BINS])o.lower,
                                   (const hairobb__b4 (*)[HAIROBB__BINS])o.upper, (const uint32_t (*)[4])o.count,
                                   box_cost, frame, origins, scales, best);
        } else
#endif
        {
            for (axis = 0; axis < 3; ++axis) {
                float lower[HAIROBB__BINS][3], upper[HAIROBB__BINS][3];
                size_t counts[HAIROBB__BINS];
                if (!(scales[axis] > 0.0f)) continue;
                for (bin = 0; bin < bins; ++bin) {
                    hairobb__b4_store3(lower[bin], o.lower[axis][bin]);
                    hairobb__b4_store3(upper[bin], o.upper[axis][bin]);
                    counts[bin] = o.count[bin][axis];
                }
                hairobb__sweep_bins(bins, (const float (*)[3])lower, (const float (*)[3])upper, counts, counts, box_cost,
                                    HAIROBB__SPLIT_OBJECT, frame, axis, origins[axis], scales[axis], best);
            }
        }
    }
    for (axis = 0; axis < 3 && spatial_slack > 0; ++axis)
        hairobb__spatial_bins(b, r, frame, axis, bins, bmin, bmax, box_cost, spatial_slack, best);
}

/* ------------------------------------------------------------------------ */
/* >>splits  Builder: splits (clusters, node boxes, the cheapest split)     */
/* ------------------------------------------------------------------------ */
/* Which of two main directions a reference is closer to (0 or 1). */
static int hairobb__cluster_of(const hairobb__builder *b, size_t i, const float direction[2][3])
{
    float d[3];
    if (!hairobb__ref_direction(b, i, d)) return 0;
    return fabsf(hairobb__dot3(d, direction[1])) > fabsf(hairobb__dot3(d, direction[0]));
}

/* Similar-orientation clustering: the main direction of the middle reference
   (A) and of the sampled reference most misaligned with it (B); each
   reference joins the one its own direction is closer to, and each cluster
   is bounded in its own hair space. */
static void hairobb__cluster_split(const hairobb__builder *b, const hairobb__range *r, float box_cost, hairobb__split *best)
{
    size_t count = r->end - r->begin, step = count > HAIROBB__SAMPLE ? count / HAIROBB__SAMPLE : 1, i, n[2] = {0, 0};
    float direction[2][3], frame[9], lower[2][3], upper[2][3], best_dot = 0.9f, cost;
    hairobb__frame_prep prep[2];
    int found = 0, c;
    if (!hairobb__ref_direction(b, r->begin + count / 2, direction[0])) return;
    for (i = r->begin; i < r->end; i += step) {
        float d[3], dot;
        if (!hairobb__ref_direction(b, i, d)) continue;
        dot = fabsf(hairobb__dot3(d, direction[0]));
        if (dot < best_dot) { best_dot = dot; memcpy(direction[1], d, sizeof d); found = 1; }
    }
    if (!found) return;     /* all within ~25 degrees: hair-space binning covers it */
    for (c = 0; c < 2; ++c) {
        hairobb__frame_from_direction(direction[c], frame);
        hairobb__prepare_frame(frame, &prep[c]);
        hairobb__box_empty(lower[c], upper[c]);
    }
    for (i = r->begin; i < r->end; ++i) {
        float lo[3], hi[3];
        c = hairobb__cluster_of(b, i, (const float (*)[3])direction);
        hairobb__prim_box(b, i, &prep[c], lo, hi);
        hairobb__box_grow(lower[c], upper[c], lo, hi);
        n[c]++;
    }
    if (n[0] == 0 || n[1] == 0) return;
    cost = box_cost + HAIROBB__COST_SEGMENT * (hairobb__half_area(lower[0], upper[0]) * (float)n[0] +
                                               hairobb__half_area(lower[1], upper[1]) * (float)n[1]);
    if (cost < best->cost) {
        best->cost = cost;
        best->kind = HAIROBB__SPLIT_CLUSTER;
        best->heuristic = HAIROBB__TRY_CLUSTER;
        best->hair_space = 1;
        memcpy(best->direction, direction, sizeof direction);
        best->area_left = hairobb__half_area(lower[0], upper[0]);
        best->area_right = hairobb__half_area(lower[1], upper[1]);
    }
}

/* World box of the references at positions [begin, end). */
static void hairobb__range_box(const hairobb__builder *b, size_t begin, size_t end, float lower[3], float upper[3])
{
    size_t i;
    hairobb__box_empty(lower, upper);
    for (i = begin; i < end; ++i) hairobb__box_grow(lower, upper, b->world_boxes + 6 * i, b->world_boxes + 6 * i + 3);
}

/* The box of positions [begin, end) in a prepared frame, with node_box's radius scale. */
HAIROBB__INLINE void hairobb__positions_box(const hairobb__builder *b, size_t begin, size_t end, const hairobb__frame_prep *prep,
                                            const float *centre, const float norms[3], hairobb__b4 *lower, hairobb__b4 *upper)
{
    size_t i;
    hairobb__b4 box_lower = hairobb__b4_set1(FLT_MAX), box_upper = hairobb__b4_set1(-FLT_MAX);
    for (i = begin; i < end; ++i) {
        hairobb__b4 lo, hi;
        hairobb__prefetch_points(b, i, end);
        hairobb__ref_box_v4(b, i, prep, centre, norms, &lo, &hi);
        box_lower = hairobb__b4_min(box_lower, lo);
        box_upper = hairobb__b4_max(box_upper, hi);
    }
    *lower = box_lower;
    *upper = box_upper;
}

/* A top node's child box in parts (hairobb__top_parts). */
typedef struct hairobb__boxing {
    const hairobb__builder *b;
    const hairobb__range *r;
    const hairobb__frame_prep *prep;
    const float *centre, *norms;
    size_t parts;
    hairobb__b4 lower[HAIROBB__TOP_PARTS], upper[HAIROBB__TOP_PARTS];
} hairobb__boxing;

static void hairobb__box_part(void *context, unsigned k)
{
    hairobb__boxing *w = HAIROBB__CAST(hairobb__boxing *, context);
    size_t begin, end;
    hairobb__part_items(w->r->end - w->r->begin, w->parts, k, &begin, &end);
    hairobb__positions_box(w->b, w->r->begin + begin, w->r->begin + end, w->prep, w->centre, w->norms, &w->lower[k], &w->upper[k]);
}

/* The padded box of the range in frame around centre: what a node stores. */
static void hairobb__node_box(const hairobb__builder *b, const hairobb__range *r, const float frame[9],
                              const float *centre, float lower[3], float upper[3])
{
    size_t count = r->end - r->begin, parts = hairobb__top_part_count(b, count);
    float norms[3];
    int k;
    hairobb__frame_prep prep;
    hairobb__b4 box_lower, box_upper;
    hairobb__prepare_frame(frame, &prep);
    for (k = 0; k < 3; ++k)     /* rounded up: the radius must not shrink */
        norms[k] = sqrtf(hairobb__dot3(frame + 3 * k, frame + 3 * k)) * (1.0f + 1.0f / 1048576.0f);
    if (parts > 1) {
        hairobb__boxing w;
        size_t part;
        w.b = b; w.r = r; w.prep = &prep; w.centre = centre; w.norms = norms;
        w.parts = parts;
        hairobb__top_parts(b, w.parts, hairobb__box_part, &w);
        box_lower = w.lower[0];
        box_upper = w.upper[0];
        for (part = 1; part < w.parts; ++part) {
            box_lower = hairobb__b4_min(box_lower, w.lower[part]);
            box_upper = hairobb__b4_max(box_upper, w.upper[part]);
        }
    } else {
        hairobb__positions_box(b, r->begin, r->end, &prep, centre, norms, &box_lower, &box_upper);
    }
    hairobb__b4_store3(lower, box_lower);
    hairobb__b4_store3(upper, box_upper);
    hairobb__pad_box(lower, upper);
}

/* A float point near the middle of a world box: an OBB or compressed
   node's centre (the builder's, and the refit's from its new box). */
static void hairobb__box_centre(const float lower[3], const float upper[3], float centre[3])
{
    int k;
    for (k = 0; k < 3; ++k) centre[k] = 0.5f * lower[k] + 0.5f * upper[k];
}

/* The centre of the ranges' world box. */
static void hairobb__range_centre(const hairobb__builder *b, const hairobb__range *ranges, int range_count, float centre[3])
{
    float lower[3], upper[3], lo[3], hi[3];
    int i;
    hairobb__box_empty(lower, upper);
    for (i = 0; i < range_count; ++i) {
        hairobb__range_box(b, ranges[i].begin, ranges[i].end, lo, hi);
        hairobb__box_grow(lower, upper, lo, hi);
    }
    hairobb__box_centre(lower, upper, centre);
}

/* Above the tasks: the ranges the calling thread splits alone. */
static int hairobb__at_top(const hairobb__builder *b, size_t count) { return b->task_limit && count > b->task_limit; }

/* The cheapest split the policy and the subtree's tries allow; a median split
   when none is found (all centroids equal) or below the SAH depth. */
/* hair_space: the frame hairobb__choose_hair_space(b, r, 1, 0, .) gives, if
   known (NULL: chosen here). */
static void hairobb__find_split(hairobb__builder *b, const hairobb__range *r, unsigned depth,
                                unsigned tries, const float *hair_space, hairobb__split *best)
{
    float lower[3], upper[3], area = 0.0f;
    size_t slack = (tries & HAIROBB__TRY_SPATIAL) ? r->cap - r->end : 0;
    int world_binning = depth < HAIROBB__SAH_DEPTH && b->policy != HAIROBB_NODES_OBB_ONLY;
    if (!world_binning) {   /* else the binning's first pass finds the same box */
        hairobb__range_box(b, r->begin, r->end, lower, upper);
        area = hairobb__half_area(lower, upper);
    }
    best->cost = FLT_MAX;
    best->kind = HAIROBB__SPLIT_MEDIAN;
    best->heuristic = 0;
    best->hair_space = 0;
    if (depth < HAIROBB__SAH_DEPTH) {
        if (world_binning) hairobb__bin_split(b, r, NULL, 2.0f * HAIROBB__COST_AABB, &area, slack, best);
        /* a mixed tree's top (above the tasks) splits in world space only: hair
           is sorted by place there, where hair space seldom wins, and that
           part of the build is not spread over threads: fewer build
           instructions at the same traced ones */
        if (b->policy != HAIROBB_NODES_AABB_ONLY && (tries & HAIROBB__TRY_HAIR_SPACE) &&
            (b->policy == HAIROBB_NODES_OBB_ONLY || !hairobb__at_top(b, r->end - r->begin))) {
            float frame[9];
            if (hair_space) memcpy(frame, hair_space, sizeof frame);
            else hairobb__choose_hair_space(b, r, 1, 0, frame);
            b->frame_first = r->begin;      /* the frame boxes are r's until the next split */
            hairobb__bin_split(b, r, frame, 2.0f * HAIROBB__COST_OBB, &area, slack, best);
        }
        if (b->policy != HAIROBB_NODES_AABB_ONLY && (tries & HAIROBB__TRY_CLUSTER))
            hairobb__cluster_split(b, r, 2.0f * HAIROBB__COST_OBB * area, best);
    }
    best->parent_area = area;
    if (best->kind == HAIROBB__SPLIT_MEDIAN) {
        size_t half = (r->end - r->begin) / 2;
        best->cost = FLT_MAX;
        hairobb__range_box(b, r->begin, r->begin + half, lower, upper);
        best->area_left = hairobb__half_area(lower, upper);
        hairobb__range_box(b, r->begin + half, r->end, lower, upper);
        best->area_right = hairobb__half_area(lower, upper);
    }
}

/* "Skip what a scene doesn't need": spatial splits or clustering that won
   none of HAIROBB__STRIKES splits in a row on the way down (below the top
   of the tree, which is split by place) are not tried in the subtree
   below. Hair-space binning is always tried: it loses near the root, where
   hair is sorted by place, and wins most splits below, so no early verdict
   on it holds. */
static void hairobb__update_tries(hairobb__tries *t, const hairobb__split *split)
{
    int h;
    for (h = 1; h < 3; ++h) {
        unsigned bit = 1u << h;
        if (!(t->enabled & bit)) continue;
        if (split->cost == FLT_MAX || (split->heuristic & bit)) t->losses[h] = 0;
        else if (++t->losses[h] >= HAIROBB__STRIKES) t->enabled &= ~bit;
    }
}

/* ------------------------------------------------------------------------ */
/* >>partition  Builder: partition (and clipping for spatial splits)        */
/* ------------------------------------------------------------------------ */
/* Swaps the references at positions i and j. Boxes in the frame last
   binned are read only by the partition's test of the position it looks at
   next: with frame_box, i (looked at next) gets j's; the rest are stale
   after the partition and are not moved. */
HAIROBB__INLINE void hairobb__swap_positions(hairobb__builder *b, size_t i, size_t j, int frame_box)
{
    uint32_t id = b->ids[i];
    float box[6];
    memcpy(box, b->world_boxes + 6 * i, sizeof box);
    b->ids[i] = b->ids[j];
    memcpy(b->world_boxes + 6 * i, b->world_boxes + 6 * j, sizeof box);
    b->ids[j] = id;
    memcpy(b->world_boxes + 6 * j, box, sizeof box);
    if (b->ranges) {
        float range[2];
        memcpy(range, b->ranges + 2 * i, sizeof range);
        memcpy(b->ranges + 2 * i, b->ranges + 2 * j, sizeof range);
        memcpy(b->ranges + 2 * j, range, sizeof range);
    }
    if (frame_box) memcpy(hairobb__frame_box(b, i), hairobb__frame_box(b, j), sizeof box);
}

static void hairobb__set_range(hairobb__builder *b, size_t i, float u0, float u1)
{
    float identity[9];
    hairobb__frame_prep prep;
    if (b->ranges) {
        b->ranges[2 * i] = u0;
        b->ranges[2 * i + 1] = u1;
    }
    hairobb__identity_frame(identity);
    hairobb__prepare_frame(identity, &prep);
    hairobb__ref_box(b, i, &prep, NULL, NULL, b->world_boxes + 6 * i, b->world_boxes + 6 * i + 3);
}

/* Side of a reference for split: 0 left, 1 right, 2 straddling a spatial
   plane. A hair-space split was just binned: its boxes are in frame_boxes. */
static int hairobb__side(const hairobb__builder *b, size_t i, const hairobb__split *split)
{
    const float *box;
    if (split->kind == HAIROBB__SPLIT_CLUSTER) return hairobb__cluster_of(b, i, split->direction);
    box = (split->hair_space ? hairobb__frame_box(b, i) : b->world_boxes + 6 * i) + split->axis;   /* box[0] lower, box[3] upper */
    if (split->kind == HAIROBB__SPLIT_SPATIAL) {
        int first = hairobb__bin_of(box[0], split->bin_origin, split->bin_scale);
        int last = hairobb__bin_of(box[3], split->bin_origin, split->bin_scale);
        return last <= split->last_left_bin ? 0 : first > split->last_left_bin ? 1 : 2;
    }
    return hairobb__bin_of(0.5f * (box[0] + box[3]), split->bin_origin, split->bin_scale) > split->last_left_bin;
}

/* Clips the straddling reference at position i at the split plane: i keeps
   the part on one side, position `extra` gets the other; the side i's part
   lies on is returned. A reference whose centre line does not cross the
   plane between its ends is not clipped (returns 0, extra unused: -1). */
static int hairobb__clip(hairobb__builder *b, size_t i, size_t extra, const hairobb__split *split)
{
    float frame_row[3] = {0.0f, 0.0f, 0.0f}, plane, u0 = b->ranges[2 * i], u1 = b->ranges[2 * i + 1];
    float lo = u0, hi = u1, c0, c1, uc, converted[16];
    const float *cp = hairobb__builder_points(b, b->vertices, b->ids[i], converted);
    int iteration, k;
    if (split->hair_space) memcpy(frame_row, split->frame + 3 * split->axis, sizeof frame_row);
    else frame_row[split->axis] = 1.0f;
    plane = split->bin_origin + (float)(split->last_left_bin + 1) / split->bin_scale;
    /* the centre line's coordinate along the plane's normal, in the whole segment's u */
#define HAIROBB__COORD(u) (frame_row[0] * hairobb__bezier4(cp, 0, u) + frame_row[1] * hairobb__bezier4(cp, 1, u) + \
                           frame_row[2] * hairobb__bezier4(cp, 2, u) - plane)
    c0 = HAIROBB__COORD(u0);
    c1 = HAIROBB__COORD(u1);
    if (!((c0 < 0.0f && c1 > 0.0f) || (c0 > 0.0f && c1 < 0.0f))) return -1;
    for (iteration = 0; iteration < 24; ++iteration) {
        float mid = 0.5f * (lo + hi), cm = HAIROBB__COORD(mid);
        if (mid <= lo || mid >= hi) break;
        if ((cm < 0.0f) == (c0 < 0.0f)) lo = mid; else hi = mid;
    }
#undef HAIROBB__COORD
    uc = 0.5f * (lo + hi);
    if (!(uc > u0 && uc < u1)) return -1;
    b->ids[extra] = b->ids[i];
    hairobb__set_range(b, extra, uc, u1);
    hairobb__set_range(b, i, u0, uc);
    k = c0 < 0.0f ? 0 : 1;      /* i keeps [u0, uc], which starts on side k */
    return k;
}

/* Moves positions [from, end) to start at `to` (to >= from). */
static void hairobb__shift_positions(hairobb__builder *b, size_t from, size_t end, size_t to)
{
    size_t n = end - from;
    if (to == from || n == 0) return;
    memmove(b->ids + to, b->ids + from, n * sizeof *b->ids);
    if (b->ranges) memmove(b->ranges + 2 * to, b->ranges + 2 * from, 2 * n * sizeof *b->ranges);
    memmove(b->world_boxes + 6 * to, b->world_boxes + 6 * from, 6 * n * sizeof *b->world_boxes);
}

/* Splits range r into *left and *right: left's references first; spatial
   splits clip the straddling ones, appending the extra parts in r's slack.
   The remaining slack is shared in proportion to the two sides' sizes. */
static void hairobb__partition(hairobb__builder *b, const hairobb__range *r, const hairobb__split *split,
                               hairobb__range *left, hairobb__range *right)
{
    size_t lo = r->begin, mid = r->begin, hi = r->end, end = r->end, i, left_count, right_count, slack, share;
    if (split->kind == HAIROBB__SPLIT_MEDIAN) {
        mid = r->begin + (r->end - r->begin) / 2;
        lo = mid;
    } else {
        /* three-way: [begin, lo) left, [lo, mid) straddling, [hi, end) right */
        int frame_box = split->hair_space && split->kind != HAIROBB__SPLIT_CLUSTER;
        if (split->kind == HAIROBB__SPLIT_OBJECT) {
            /* hairobb__side's object test written out: no reference straddles, lo stays mid */
            /* box + 6 * (i - r->begin): position i's */
            const float *box = (frame_box ? hairobb__frame_box(b, r->begin) : b->world_boxes + 6 * r->begin) + split->axis;
            while (mid < hi) {
                const float *at = box + 6 * (mid - r->begin);
                if (hairobb__bin_of(0.5f * (at[0] + at[3]), split->bin_origin, split->bin_scale) <= split->last_left_bin)
                    mid++;
                else if (mid < --hi)
                    hairobb__swap_positions(b, mid, hi, frame_box);
            }
            lo = mid;
        }
        while (mid < hi) {
            int side = hairobb__side(b, mid, split);
            if (side == 0) {
                if (lo < mid) hairobb__swap_positions(b, lo, mid, 0);
                lo++, mid++;
            } else if (side == 2) {
                mid++;
            } else if (mid < --hi) {
                hairobb__swap_positions(b, mid, hi, frame_box);
            }
        }
        /* clip the straddling references: the left part stays, the right part
           is appended after the right side */
        for (i = lo; i < mid; ++i) {
            int side;
            HAIROBB_ASSERT(end < r->cap);
            side = hairobb__clip(b, i, end, split);
            if (side < 0) continue;                 /* kept whole, on the left */
            if (side == 1) hairobb__swap_positions(b, i, end, 0);
            ++end;
        }
        lo = mid;
    }
    left_count = lo - r->begin;
    right_count = end - lo;
    if (left_count == 0 || right_count == 0) {
        /* the plane cut nothing apart after all: fall back to the median */
        hairobb__split median = *split;
        hairobb__range whole = *r;
        median.kind = HAIROBB__SPLIT_MEDIAN;
        whole.end = end;
        hairobb__partition(b, &whole, &median, left, right);
        return;
    }
    slack = r->cap - end;
    share = (size_t)((double)slack * (double)left_count / (double)(left_count + right_count));
    hairobb__shift_positions(b, lo, end, lo + share);
    left->begin = r->begin; left->end = lo; left->cap = lo + share;
    right->begin = lo + share; right->end = end + share; right->cap = r->cap;
}

/* ------------------------------------------------------------------------ */
/* >>node_store  Builder: node memory, progress, leaves                     */
/* ------------------------------------------------------------------------ */
/* Node memory starts at a 64-byte boundary inside what HAIROBB_MALLOC gave
   (bytes + 64 of it). */
static unsigned char *hairobb__align64(unsigned char *allocation)
{
    return allocation + ((64 - ((uintptr_t)allocation & 63)) & 63);
}

/* Node memory grows by doubling; offsets, not pointers, survive a move. */
static size_t hairobb__alloc_node(hairobb__builder *b, size_t bytes)
{
    size_t offset = b->node_bytes;
    if (b->error != HAIROBB_OK) return 0;
    if (offset + bytes > b->node_capacity) {
        size_t capacity = b->node_capacity ? 2 * b->node_capacity : b->node_reserve > 4096 ? b->node_reserve : 4096;
        unsigned char *allocation, *aligned;
        while (capacity < offset + bytes) capacity *= 2;
        allocation = HAIROBB__CAST(unsigned char *, hairobb__malloc_large(capacity + 64, b->user));
        if (!allocation) { b->error = HAIROBB_ERROR_OUT_OF_MEMORY; return 0; }
        aligned = hairobb__align64(allocation);
        if (b->node_bytes) memcpy(aligned, b->nodes, b->node_bytes);
        if (b->node_allocation) HAIROBB_FREE(b->node_allocation, b->user);
        b->node_allocation = allocation;
        b->nodes = aligned;
        b->node_capacity = capacity;
    }
    b->node_bytes += bytes;
    return offset;
}

typedef struct hairobb__child {
    hairobb__range range;
    float area;
    int final_leaf;             /* SAH chose a leaf for it */
} hairobb__child;

/* The serial top of the tree's share of the progress fraction: about its
   share of a one-thread build's instructions (callgrind: about a fifth). */
#define HAIROBB__TOP_SHARE 0.2

/* Reports progress (on the calling thread, where task_limit is set): the
   top's splits so far against their estimate, then the positions leaves
   and tasks finished; each part rises, so the fraction does. */
static void hairobb__report_progress(hairobb__builder *b)
{
    double share = b->top_work ? HAIROBB__TOP_SHARE : 0.0;   /* no top: all tasks */
    double top = b->top_work ? (double)b->top_done / (double)b->top_work : 0.0, fraction;
    if (!b->progress || !b->task_limit || b->error != HAIROBB_OK) return;
    fraction = share * (top < 1.0 ? top : 1.0) + (1.0 - share) * (double)b->positions_done / (double)b->capacity;
    /* the last report, 1, comes when the tree is complete */
    if (fraction < (double)b->next_report || fraction >= 1.0) return;
    b->next_report = (float)fraction + 1.0f / 128.0f;
    if (b->progress(b->progress_user, (float)fraction)) b->error = HAIROBB_ERROR_CANCELLED;
}

/* A leaf (or a task) finishes the positions [begin, cap) of its range. */
static void hairobb__finish_positions(hairobb__builder *b, size_t count)
{
    b->positions_done += count;
    hairobb__report_progress(b);
}

/* A leaf names positions of ids; hairobb__finish_tree copies them out in
   tree order once the build is done. */
static uint64_t hairobb__make_leaf(hairobb__builder *b, const hairobb__range *r, unsigned depth)
{
    size_t start = r->begin, i;
    if (b->segment_of)      /* the task's local ids back to segments: nothing reads these positions again */
        for (i = r->begin; i < r->end; ++i) b->ids[i] = b->segment_of[b->ids[i]];
    b->stats.leaves++;
    b->stats.leaf_references += r->end - r->begin;
    if (depth > b->stats.max_depth) b->stats.max_depth = depth;
    hairobb__finish_positions(b, r->cap - r->begin);
    return ((uint64_t)start << 8) | ((uint64_t)(r->end - r->begin) << 4) | HAIROBB__REF_LEAF;
}

/* ------------------------------------------------------------------------ */
/* >>layouts  Node layouts: each layout's struct and writer                 */
/* ------------------------------------------------------------------------ */
/* The node layouts the builder writes and the traversal reads, each
   struct with its writer; hairobb__write_boxes picks the writer of a
   node's type. The traversal's test of each layout is with the kernels
   (>>traversal), which are compiled once more for AVX2. */

/* Four axis-aligned child boxes, struct of arrays: 128 bytes. */
typedef struct hairobb__aabb_node {
    float lower[3][HAIROBB__W], upper[3][HAIROBB__W];   /* [axis][child] */
    uint64_t child[HAIROBB__W];
} hairobb__aabb_node;

/* Four boxes in one rotated frame, the node's hair space, around a centre:
   the ray is moved and rotated once, then tested as in an AABB node: 176 bytes. */
typedef struct hairobb__rotated_node {
    float rotation[9], centre[3];     /* rows: the frame's axes */
    float lower[3][HAIROBB__W], upper[3][HAIROBB__W];   /* [axis][child], of R * (p - centre) */
    uint64_t child[HAIROBB__W];
} hairobb__rotated_node;

/* AABB and rotated nodes: all boxes in float, in one frame (the world
   axes, no centre, for AABB). axis_boxes: see hairobb__write_boxes. */
static void hairobb__write_one_frame_node(const hairobb__builder *b, unsigned char *node_memory, unsigned node_type,
                                          const float centre[3], const hairobb__range *ranges, int count,
                                          const float (*frames)[9], const float (*axis_boxes)[6])
{
    int i, k;
    float (*lower)[HAIROBB__W], (*upper)[HAIROBB__W];
    const float *box_centre = NULL;
    if (node_type == HAIROBB__REF_ROTATED) {
        hairobb__rotated_node *node = HAIROBB__CAST(hairobb__rotated_node *, (void *)node_memory);
        memcpy(node->centre, centre, sizeof node->centre);
        box_centre = node->centre;
        lower = node->lower; upper = node->upper;
    } else {
        hairobb__aabb_node *node = HAIROBB__CAST(hairobb__aabb_node *, (void *)node_memory);
        lower = node->lower; upper = node->upper;
    }
    for (i = 0; i < HAIROBB__W; ++i) {
        float lo[3], hi[3];
        if (i < count && axis_boxes && node_type == HAIROBB__REF_AABB) {
            memcpy(lo, axis_boxes[i], sizeof lo);
            memcpy(hi, axis_boxes[i] + 3, sizeof hi);
            hairobb__pad_box(lo, hi);
        } else if (i < count) {
            hairobb__node_box(b, &ranges[i], frames[0], box_centre, lo, hi);
        } else { for (k = 0; k < 3; ++k) { lo[k] = INFINITY; hi[k] = -INFINITY; } }
        for (k = 0; k < 3; ++k) { lower[k][i] = lo[k]; upper[k][i] = hi[k]; }
    }
}

/* Four oriented child boxes, each an affine map of world space onto the unit
   cube: unit = M * (p - centre) + m, with xfm[0..8] = M row-major and
   xfm[9..11] = m, each entry holding all children. Subtracting a centre
   near the node first keeps the transform's rounding proportional to the
   distance between ray origin and node, not to their distance from the
   world origin: 240 bytes. */
typedef struct hairobb__obb_node {
    float centre[4];                  /* xyz, w unused */
    float xfm[12][HAIROBB__W];
    uint64_t child[HAIROBB__W];
} hairobb__obb_node;

/* Writes the affine map of box [lower, upper] in frame onto the unit cube
   into lane `lane` of an OBB node. */
static void hairobb__store_obb(hairobb__obb_node *node, int lane, const float frame[9],
                               const float lower[3], const float upper[3])
{
    int row, col;
    for (row = 0; row < 3; ++row) {
        /* a floor on the extent keeps the scale finite for flat boxes */
        float extent = hairobb__maxf(upper[row] - lower[row], 1e-30f);
        float scale = 1.0f / extent;
        for (col = 0; col < 3; ++col) node->xfm[3 * row + col][lane] = frame[3 * row + col] * scale;
        node->xfm[9 + row][lane] = -lower[row] * scale;
    }
}

/* An affine OBB node's boxes: child i's map from frames[i]. */
static void hairobb__write_obb_node(const hairobb__builder *b, unsigned char *node_memory, const float centre[3],
                                    const hairobb__range *ranges, int count, const float (*frames)[9])
{
    int i;
    hairobb__obb_node *node = HAIROBB__CAST(hairobb__obb_node *, (void *)node_memory);
    memcpy(node->centre, centre, 3 * sizeof(float));
    node->centre[3] = 0.0f;
    for (i = 0; i < HAIROBB__W; ++i) {
        float frame[9], lower[3], upper[3];
        if (i < count) {
            memcpy(frame, frames[i], sizeof frame);
            hairobb__node_box(b, &ranges[i], frame, node->centre, lower, upper);
        } else {
            /* an empty child maps everything to (2,2,2): never inside the unit cube */
            memset(frame, 0, sizeof frame);
            lower[0] = lower[1] = lower[2] = -2.0f;
            upper[0] = upper[1] = upper[2] = -1.0f;
        }
        hairobb__store_obb(node, i, frame, lower, upper);
    }
}

/* The frame a compressed node's bytes decode to: the rotation times 127,
   left unscaled (slab distances do not change with the scale, and the
   traversal saves the multiplies); both builder and traversal use it. */
HAIROBB__INLINE void hairobb__decode_rotation(const signed char q[9], float frame[9])
{
    int k;
    for (k = 0; k < 9; ++k) frame[k] = (float)q[k];
}

/* Child boxes (in the node's frame, around its centre) to bytes: a step per
   axis so the largest coordinate fits 127 steps, then each plane rounded
   outward and checked against the product the traversal computes. */
static void hairobb__store_compressed(float step_out[3], signed char (*lower_bytes)[HAIROBB__W],
                                      signed char (*upper_bytes)[HAIROBB__W], int count,
                                      const float lower[][3], const float upper[][3])
{
    int i, k;
    for (k = 0; k < 3; ++k) {
        float largest = 0.0f, step;
        for (i = 0; i < count; ++i) largest = hairobb__maxf(largest, hairobb__maxf(fabsf(lower[i][k]), fabsf(upper[i][k])));
        step = hairobb__maxf(largest * (1.0f / 127.0f) * (1.0f + 1.0f / 65536.0f), 1e-30f);
        while (127.0f * step < largest) step = nextafterf(step, FLT_MAX);
        step_out[k] = step;
        for (i = 0; i < HAIROBB__W; ++i) {
            int lo = 127, hi = -128;      /* empty lane: lower above upper */
            if (i < count) {
                /* floorf and ceilf of quotients within +-128 (a call each without SSE4.1) */
                float l = lower[i][k] / step, h = upper[i][k] / step;
                lo = (int)l; lo -= (float)lo > l;
                hi = (int)h; hi += (float)hi < h;
                lo = lo < -127 ? -127 : lo;
                hi = hi > 127 ? 127 : hi;
                while (lo > -127 && (float)lo * step > lower[i][k]) --lo;
                while (hi < 127 && (float)hi * step < upper[i][k]) ++hi;
            }
            lower_bytes[k][i] = (signed char)lo;
            upper_bytes[k][i] = (signed char)hi;
        }
    }
}

/* The paper's compressed node: the boxes of all children in one hair space
   (a rotation quantised to signed bytes q = 127 R, used as the frame q
   itself; the identity for an axis-aligned node) around a float centre, each child box as signed bytes
   times a per-axis float step, rounded outward: 96 bytes 4-wide, 160 8-wide. */
typedef struct hairobb__compressed_node {
    float centre[3], step[3];
    signed char rotation[9];          /* rows of the frame times 127 */
    signed char lower[3][HAIROBB__W], upper[3][HAIROBB__W];   /* [axis][child] in steps */
    unsigned char pad[HAIROBB__W == 8 ? 15 : 7];              /* child[] at a multiple of 16 */
    uint64_t child[HAIROBB__W];
} hairobb__compressed_node;
typedef char hairobb__compressed_node_size[sizeof(hairobb__compressed_node) == (HAIROBB__W == 8 ? 160 : 96) ? 1 : -1];

/* The paper's compressed node's boxes (axis-aligned or rotated), in bytes
   of frames[0]. */
static void hairobb__write_compressed_node(const hairobb__builder *b, unsigned char *node_memory, const float centre[3],
                                           const hairobb__range *ranges, int count, const float (*frames)[9])
{
    int i;
    hairobb__compressed_node *node = HAIROBB__CAST(hairobb__compressed_node *, (void *)node_memory);
    float lower[HAIROBB__W][3], upper[HAIROBB__W][3];
    memcpy(node->centre, centre, 3 * sizeof(float));
    for (i = 0; i < count; ++i) hairobb__node_box(b, &ranges[i], frames[0], node->centre, lower[i], upper[i]);
    hairobb__store_compressed(node->step, node->lower, node->upper, count, (const float (*)[3])lower, (const float (*)[3])upper);
}

/* Compressed with a rotation per child, as the per-child affine node: each
   child's box is in its own frame rotation[.][child] (127 R), around the
   node's centre, in steps shared by the node: 128 bytes 4-wide, 208 8-wide. */
typedef struct hairobb__compressed_obb_node {
    float centre[3], step[3];
    signed char rotation[9][HAIROBB__W];                      /* [entry][child] */
    signed char lower[3][HAIROBB__W], upper[3][HAIROBB__W];   /* [axis][child] in steps */
#if HAIROBB__W == 4
    unsigned char pad[12];                                    /* child[] at a multiple of 16 */
#endif
    uint64_t child[HAIROBB__W];
} hairobb__compressed_obb_node;
typedef char hairobb__compressed_obb_node_size[sizeof(hairobb__compressed_obb_node) == (HAIROBB__W == 8 ? 208 : 128) ? 1 : -1];

/* A compressed per-child node's boxes, in bytes of each child's frame. */
static void hairobb__write_compressed_obb_node(const hairobb__builder *b, unsigned char *node_memory, const float centre[3],
                                               const hairobb__range *ranges, int count, const float (*frames)[9])
{
    int i, k;
    hairobb__compressed_obb_node *node = HAIROBB__CAST(hairobb__compressed_obb_node *, (void *)node_memory);
    float lower[HAIROBB__W][3], upper[HAIROBB__W][3];
    memcpy(node->centre, centre, 3 * sizeof(float));
    for (i = 0; i < count; ++i) hairobb__node_box(b, &ranges[i], frames[i], node->centre, lower[i], upper[i]);
    hairobb__store_compressed(node->step, node->lower, node->upper, count, (const float (*)[3])lower, (const float (*)[3])upper);
    /* Empty lanes: the identity and the point box at -128 steps on each
       axis, outside every child. An inverted box would not do: this
       node's test takes each slab's planes in either order, which turns
       it into the whole cube of steps: rays would visit empty children. */
    for (i = count; i < HAIROBB__W; ++i) {
        node->rotation[0][i] = node->rotation[4][i] = node->rotation[8][i] = 127;
        for (k = 0; k < 3; ++k) node->lower[k][i] = node->upper[k][i] = -128;
    }
}

static size_t hairobb__node_size(unsigned node_type)
{
    switch (HAIROBB__STILL_TYPE(node_type)) {
    case HAIROBB__REF_AABB: return sizeof(hairobb__aabb_node);
    case HAIROBB__REF_OBB: return sizeof(hairobb__obb_node);
    case HAIROBB__REF_ROTATED: return sizeof(hairobb__rotated_node);
    case HAIROBB__REF_QOBB_PER_CHILD: return sizeof(hairobb__compressed_obb_node);
    default: return sizeof(hairobb__compressed_node);
    }
}

/* Bytes of a moving node's planes at time 1, after the node: lower and
   upper bytes [6][W] as the node's own, to a multiple of 16. */
#define HAIROBB__END_PLANES ((6 * HAIROBB__W + 15) / 16 * 16)

/* Node memory a node takes: the node, and after an affine OBB node the
   main direction of each child's frame (3 floats, a multiple of 16 bytes
   per node), which its maps no longer give exactly; the traversal never
   reads them, hairobb_refit rebuilds the frames from them. A moving node's
   planes at time 1 follow it. */
static size_t hairobb__node_stride(unsigned node_type)
{
    return hairobb__node_size(node_type) + (node_type == HAIROBB__REF_OBB ? HAIROBB__W * 3 * sizeof(float) : 0) +
           (HAIROBB__MOVING(node_type) ? HAIROBB__END_PLANES : 0);
}

/* Linear bounds of a moving range: its boxes at time 0 and time 1 in frame
   around centre, whose lerp holds the range at every time. Each step's box
   is bounded as a still one (the ribbon at a step's time is the still
   ribbon of those points); the lines through the first and the last step's
   planes are moved out by the most any other step sticks out of them, so
   they hold every step, and the points in between, which move linearly.
   Padded as hairobb__pad_box, and for the leaf's rounding of the lerped
   points, which scales with their distance from the world origin. */
static void hairobb__node_box_ends(const hairobb__builder *b, const hairobb__range *r, const float frame[9],
                                   const float centre[3], float lower[2][3], float upper[2][3])
{
    unsigned last = b->time_steps - 1, n, step;
    double line_lower[2][3], line_upper[2][3], out_lower[3] = {0.0, 0.0, 0.0}, out_upper[3] = {0.0, 0.0, 0.0};
    float norms[3], farthest = 0.0f;
    hairobb__frame_prep prep;
    int k, e;
    hairobb__prepare_frame(frame, &prep);
    for (k = 0; k < 3; ++k) {   /* rounded up: the radius must not shrink */
        norms[k] = sqrtf(hairobb__dot3(frame + 3 * k, frame + 3 * k)) * (1.0f + 1.0f / 1048576.0f);
        farthest = hairobb__maxf(farthest, fabsf(centre[k]));
    }
    for (n = 0; n <= last; ++n) {   /* the two ends first, then the steps between */
        hairobb__b4 box_lower = hairobb__b4_set1(FLT_MAX), box_upper = hairobb__b4_set1(-FLT_MAX);
        float lo[3], hi[3];
        size_t i;
        step = n == 0 ? 0 : n == 1 ? last : n - 1;
        for (i = r->begin; i < r->end; ++i) {
            float scratch[16];
            hairobb__b4 l, h;
            hairobb__segment_box_v4(hairobb__ref_points_in(b, b->time_vertices[step], i, scratch), &prep, centre, norms, &l, &h);
            box_lower = hairobb__b4_min(box_lower, l);
            box_upper = hairobb__b4_max(box_upper, h);
        }
        hairobb__b4_store3(lo, box_lower);
        hairobb__b4_store3(hi, box_upper);
        for (k = 0; k < 3; ++k) {
            double tau = (double)step / (double)last;
            if (n < 2) {
                line_lower[n][k] = lo[k];
                line_upper[n][k] = hi[k];
                continue;
            }
            out_lower[k] = fmax(out_lower[k], line_lower[0][k] + tau * (line_lower[1][k] - line_lower[0][k]) - lo[k]);
            out_upper[k] = fmax(out_upper[k], hi[k] - (line_upper[0][k] + tau * (line_upper[1][k] - line_upper[0][k])));
        }
    }
    for (k = 0; k < 3; ++k) {
        float mag = 0.0f, pad;
        for (e = 0; e < 2; ++e) {
            /* to float, outward */
            double l = line_lower[e][k] - out_lower[k], h = line_upper[e][k] + out_upper[k];
            lower[e][k] = (float)l;
            upper[e][k] = (float)h;
            if ((double)lower[e][k] > l) lower[e][k] = nextafterf(lower[e][k], -FLT_MAX);
            if ((double)upper[e][k] < h) upper[e][k] = nextafterf(upper[e][k], FLT_MAX);
            mag = hairobb__maxf(mag, hairobb__maxf(hairobb__maxf(fabsf(lower[e][k]), fabsf(upper[e][k])), upper[e][k] - lower[e][k]));
        }
        pad = (mag + 2.0f * norms[k] * farthest) * (1.0f / 2097152.0f) + 1e-30f;   /* 2^-21 relative */
        for (e = 0; e < 2; ++e) {
            lower[e][k] -= pad;
            upper[e][k] += pad;
        }
    }
}

/* Moving children's boxes at both ends (lower[i][end]) to bytes, planes[end]
   laid out as a compressed node's lower and upper [6][W]: a step per axis
   that fits both ends with room (1/64) for the slack, then each plane
   rounded outward by 2^-12 steps more than needed, which covers the
   traversal's lerp of the bytes (b0 + tau (b1 - b0) rounds by less than
   2^-15 steps) and its product with the step. */
static void hairobb__store_compressed_ends(float step_out[3], signed char *planes[2], int count,
                                           const float (*lower)[2][3], const float (*upper)[2][3])
{
    int i, k, e;
    for (k = 0; k < 3; ++k) {
        float largest = 0.0f, step;
        for (i = 0; i < count; ++i)
            for (e = 0; e < 2; ++e) largest = hairobb__maxf(largest, hairobb__maxf(fabsf(lower[i][e][k]), fabsf(upper[i][e][k])));
        step = hairobb__maxf(largest * (1.0f / 125.0f), 1e-30f);
        step_out[k] = step;
        for (e = 0; e < 2; ++e)
            for (i = 0; i < HAIROBB__W; ++i) {
                double lo = 127.0, hi = -128.0;      /* empty lane: lower above upper */
                if (i < count) {
                    lo = floor((double)lower[i][e][k] / step - 1.0 / 4096.0);
                    hi = ceil((double)upper[i][e][k] / step + 1.0 / 4096.0);
                    lo = lo < -127.0 ? -127.0 : lo;
                    hi = hi > 127.0 ? 127.0 : hi;
                }
                planes[e][k * HAIROBB__W + i] = (signed char)lo;
                planes[e][(3 + k) * HAIROBB__W + i] = (signed char)hi;
            }
    }
}

/* Moving hair's compressed nodes (either kind): both ends' planes. */
static void hairobb__write_moving_node(const hairobb__builder *b, unsigned char *node_memory, unsigned node_type,
                                        const float centre[3], const hairobb__range *ranges, int count, const float (*frames)[9])
{
    float lower[HAIROBB__W][2][3], upper[HAIROBB__W][2][3];
    signed char *planes[2];
    float *node_centre, *step;
    int per_child = node_type == HAIROBB__REF_QOBB_PER_CHILD_MB, i, k, e;
    if (per_child) {
        hairobb__compressed_obb_node *node = HAIROBB__CAST(hairobb__compressed_obb_node *, (void *)node_memory);
        node_centre = node->centre; step = node->step; planes[0] = node->lower[0];
    } else {
        hairobb__compressed_node *node = HAIROBB__CAST(hairobb__compressed_node *, (void *)node_memory);
        node_centre = node->centre; step = node->step; planes[0] = node->lower[0];
    }
    planes[1] = HAIROBB__CAST(signed char *, (void *)(node_memory + hairobb__node_size(node_type)));
    memcpy(node_centre, centre, 3 * sizeof(float));
    for (i = 0; i < count; ++i) hairobb__node_box_ends(b, &ranges[i], frames[per_child ? i : 0], node_centre, lower[i], upper[i]);
    hairobb__store_compressed_ends(step, planes, count, (const float (*)[2][3])lower, (const float (*)[2][3])upper);
    if (per_child) {   /* empty lanes as a still node's: the identity, a point box at -128 steps */
        hairobb__compressed_obb_node *node = HAIROBB__CAST(hairobb__compressed_obb_node *, (void *)node_memory);
        for (i = count; i < HAIROBB__W; ++i) {
            node->rotation[0][i] = node->rotation[4][i] = node->rotation[8][i] = 127;
            for (e = 0; e < 2; ++e)
                for (k = 0; k < 6; ++k) planes[e][k * HAIROBB__W + i] = -128;
        }
    }
}

/* Keeps the frames of a node's children as its type stores them (node
   zeroed): per child (affine OBB: the direction a frame was made from,
   (0,0,0) for the world axes; compressed per child: bytes), or frames[0]
   for all (rotated: floats; compressed rotated: bytes). */
static void hairobb__store_frames(unsigned char *node, unsigned node_type, int count, const float (*frames)[9])
{
    int i, k;
    node_type = HAIROBB__STILL_TYPE(node_type);
    if (node_type == HAIROBB__REF_OBB) {
        float *directions = HAIROBB__CAST(float *, (void *)(node + sizeof(hairobb__obb_node)));
        float identity[9];
        hairobb__identity_frame(identity);
        for (i = 0; i < count; ++i)
            if (memcmp(frames[i], identity, sizeof identity) != 0) memcpy(directions + 3 * i, frames[i] + 6, 3 * sizeof(float));
    } else if (node_type == HAIROBB__REF_QOBB_PER_CHILD) {
        hairobb__compressed_obb_node *q = HAIROBB__CAST(hairobb__compressed_obb_node *, (void *)node);
        for (i = 0; i < count; ++i)
            for (k = 0; k < 9; ++k) q->rotation[k][i] = (signed char)lrintf(frames[i][k] * 127.0f);
    } else if (node_type == HAIROBB__REF_QOBB) {
        hairobb__compressed_node *q = HAIROBB__CAST(hairobb__compressed_node *, (void *)node);
        for (k = 0; k < 9; ++k) q->rotation[k] = (signed char)lrintf(frames[0][k] * 127.0f);
    } else if (node_type == HAIROBB__REF_ROTATED) {
        memcpy(HAIROBB__CAST(hairobb__rotated_node *, (void *)node)->rotation, frames[0], 9 * sizeof(float));
    }
}

/* The frames the node's child boxes are in, as the traversal decodes
   them: frames[i] for child i < count, or frames[0] for all children of
   the one-frame types (axis-aligned nodes: the world axes). A frame made
   from a direction is made again from it, bit for bit. */
static void hairobb__node_frames(const unsigned char *node, unsigned node_type, int count, float (*frames)[9])
{
    int i, k;
    node_type = HAIROBB__STILL_TYPE(node_type);
    if (node_type == HAIROBB__REF_OBB) {
        const float *directions = HAIROBB__CAST(const float *, (const void *)(node + sizeof(hairobb__obb_node)));
        for (i = 0; i < count; ++i) {
            if (directions[3 * i] == 0.0f && directions[3 * i + 1] == 0.0f && directions[3 * i + 2] == 0.0f)
                hairobb__identity_frame(frames[i]);
            else
                hairobb__frame_from_direction(directions + 3 * i, frames[i]);
        }
    } else if (node_type == HAIROBB__REF_QOBB_PER_CHILD) {
        /* hairobb__decode_rotation of each lane, in the bytes' order */
        const hairobb__compressed_obb_node *q = HAIROBB__CAST(const hairobb__compressed_obb_node *, (const void *)node);
        for (k = 0; k < 9; ++k)
            for (i = 0; i < count; ++i) frames[i][k] = (float)q->rotation[k][i];
    } else if (node_type == HAIROBB__REF_QOBB) {
        hairobb__decode_rotation(HAIROBB__CAST(const hairobb__compressed_node *, (const void *)node)->rotation, frames[0]);
    } else if (node_type == HAIROBB__REF_ROTATED) {
        memcpy(frames[0], HAIROBB__CAST(const hairobb__rotated_node *, (const void *)node)->rotation, 9 * sizeof(float));
    } else {
        hairobb__identity_frame(frames[0]);
    }
}

/* Writes the boxes of a node's children, child i bounding the references
   of ranges[i] in its frame (hairobb__node_frames) around centre, and the
   node's empty lanes; its frames and child references are left as they
   are. The builder and hairobb_refit write every node with it. axis_boxes
   (a refit's; NULL: computed here) are the children's boxes in the world
   axes before padding, what an axis-aligned node stores padded: min and
   max are exact, so they can be merged from the subtrees below. */
static void hairobb__write_boxes(const hairobb__builder *b, unsigned char *node_memory, unsigned node_type,
                                 const float centre[3], const hairobb__range *ranges, int count, const float (*frames)[9],
                                 const float (*axis_boxes)[6])
{
    if (HAIROBB__MOVING(node_type))
        hairobb__write_moving_node(b, node_memory, node_type, centre, ranges, count, frames);
    else if (node_type == HAIROBB__REF_OBB)
        hairobb__write_obb_node(b, node_memory, centre, ranges, count, frames);
    else if (node_type == HAIROBB__REF_QOBB_PER_CHILD)
        hairobb__write_compressed_obb_node(b, node_memory, centre, ranges, count, frames);
    else if (node_type == HAIROBB__REF_QAABB || node_type == HAIROBB__REF_QOBB)
        hairobb__write_compressed_node(b, node_memory, centre, ranges, count, frames);
    else
        hairobb__write_one_frame_node(b, node_memory, node_type, centre, ranges, count, frames, axis_boxes);
}

/* ------------------------------------------------------------------------ */
/* >>node_build  Builder: a node of W children, a range to a subtree        */
/* ------------------------------------------------------------------------ */
static uint64_t hairobb__build_range(hairobb__builder *b, const hairobb__range *r, unsigned depth, hairobb__tries tries,
                                     const float *hair_space);
static uint64_t hairobb__add_task(hairobb__builder *b, const hairobb__range *r, unsigned depth, hairobb__tries tries);

/* SAH cost of a leaf, on the scale of hairobb__bin_split's costs */
static float hairobb__leaf_cost(size_t count, float area) { return HAIROBB__COST_SEGMENT * (float)count * area; }

/* Builds a node over range r: split the child with the largest area until
   there are W; the node is OBB where a hair-space split or a cluster won. */
static uint64_t hairobb__build_node(hairobb__builder *b, const hairobb__range *r, unsigned depth,
                                    const hairobb__split *first_split, hairobb__tries tries)
{
    hairobb__child children[HAIROBB__W];
    hairobb__range ranges[HAIROBB__W];
    /* per-child frames: the sampled sums also answer the child's own split */
    float hints[HAIROBB__W][9];
    const float *hint[HAIROBB__W];
    float frames[HAIROBB__W][9], centre[3];
    int count = 1, use_obb = b->policy == HAIROBB_NODES_OBB_ONLY, i;
    unsigned node_type;
    size_t offset, node_stride, child_offset;
    unsigned char *node;
    const uint64_t empty = HAIROBB__REF_EMPTY;
    hairobb__split split = *first_split;
    children[0].range = *r; children[0].area = FLT_MAX; children[0].final_leaf = 0;
    for (;;) {
        int pick = -1;
        hairobb__range whole;
        for (i = 0; i < count; ++i) {
            if (children[i].final_leaf || children[i].range.end - children[i].range.begin < 2) continue;
            if (pick < 0 || children[i].area > children[pick].area) pick = i;
        }
        if (pick < 0 || count == HAIROBB__W) break;
        if (count > 1) {
            size_t n = children[pick].range.end - children[pick].range.begin;
            hairobb__find_split(b, &children[pick].range, depth + 1, tries.enabled, NULL, &split);
            if (!hairobb__at_top(b, n)) hairobb__update_tries(&tries, &split);
            if (n <= b->max_leaf && hairobb__leaf_cost(n, split.parent_area) <= split.cost) {
                children[pick].final_leaf = 1;
                continue;
            }
        }
        whole = children[pick].range;
        hairobb__partition(b, &whole, &split, &children[pick].range, &children[count].range);
        if (split.hair_space) use_obb = 1;
        children[count].area = split.area_right;
        children[count].final_leaf = 0;
        children[pick].area = split.area_left;
        ++count;
    }
    if (b->policy == HAIROBB_NODES_AABB_ONLY) use_obb = 0;

    /* moving hair: the compressed layouts' moving nodes (linear bounds); no float nodes */
    if (b->time_steps && b->obb_layout == HAIROBB_OBB_COMPRESSED) node_type = use_obb ? HAIROBB__REF_QOBB_MB : HAIROBB__REF_QAABB_MB;
    else if (b->time_steps && b->obb_layout == HAIROBB_OBB_COMPRESSED_PER_CHILD)
        node_type = use_obb ? HAIROBB__REF_QOBB_PER_CHILD_MB : HAIROBB__REF_QAABB_MB;
    else if (b->obb_layout == HAIROBB_OBB_COMPRESSED) node_type = use_obb ? HAIROBB__REF_QOBB : HAIROBB__REF_QAABB;
    else if (b->obb_layout == HAIROBB_OBB_COMPRESSED_PER_CHILD)   /* float nodes near the root: see HAIROBB__FLOAT_NODES */
        node_type = !use_obb ? HAIROBB__REF_AABB : r->end - r->begin > HAIROBB__FLOAT_NODES ? HAIROBB__REF_OBB : HAIROBB__REF_QOBB_PER_CHILD;
    else if (use_obb && b->obb_layout == HAIROBB_OBB_PER_CHILD) node_type = HAIROBB__REF_OBB;
    else if (use_obb) node_type = HAIROBB__REF_ROTATED;
    else node_type = HAIROBB__REF_AABB;
    node_stride = hairobb__node_stride(node_type);
    child_offset = hairobb__node_size(node_type) - HAIROBB__W * sizeof(uint64_t);   /* every layout ends with child[W] */
    offset = hairobb__alloc_node(b, node_stride);
    if (b->error != HAIROBB_OK) return HAIROBB__REF_EMPTY;
    if (use_obb) b->stats.obb_nodes++; else b->stats.aabb_nodes++;
    /* boxes first: building the children moves references within their ranges */
    for (i = 0; i < count; ++i) ranges[i] = children[i].range;

    /* the frames first (chosen here, stored as the node keeps them, then
       decoded as the traversal and the refit decode them), then the boxes */
    node = b->nodes + offset;
    memset(node, 0, node_stride);
    for (i = 0; i < count; ++i) hint[i] = NULL;
    if (node_type == HAIROBB__REF_OBB || HAIROBB__STILL_TYPE(node_type) == HAIROBB__REF_QOBB_PER_CHILD) {
        for (i = 0; i < count; ++i) {
            hairobb__choose_hair_spaces(b, &ranges[i], 1, 1, frames[i], hints[i]);
            hint[i] = hints[i];
        }
    } else if (HAIROBB__STILL_TYPE(node_type) == HAIROBB__REF_QOBB || node_type == HAIROBB__REF_ROTATED) {
        hairobb__choose_hair_space(b, ranges, count, 1, frames[0]);
    }
    hairobb__store_frames(node, node_type, count, (const float (*)[9])frames);
    hairobb__node_frames(node, node_type, count, frames);
    hairobb__range_centre(b, ranges, count, centre);
    hairobb__write_boxes(b, node, node_type, centre, ranges, count, (const float (*)[9])frames, NULL);
    for (i = 0; i < HAIROBB__W; ++i) memcpy(node + child_offset + (size_t)i * sizeof(uint64_t), &empty, sizeof empty);
    for (i = 0; i < count; ++i) {
        const hairobb__range *c = &children[i].range;
        size_t n = c->end - c->begin;
        uint64_t ref;
        if (children[i].final_leaf || n == 1 || (count == HAIROBB__W && n <= HAIROBB__FULL_NODE_LEAF && n <= b->max_leaf))
            ref = hairobb__make_leaf(b, c, depth + 1);
        else
            ref = hairobb__build_range(b, c, depth + 1, tries, hint[i]);
        if (b->error != HAIROBB_OK) return HAIROBB__REF_EMPTY;
        /* node memory may have moved: child[] at its offset in the node */
        memcpy(b->nodes + offset + child_offset + (size_t)i * sizeof(uint64_t), &ref, sizeof ref);
    }
    return (uint64_t)offset | node_type;
}

static void hairobb__pool_lock(struct hairobb__pool *pool, int lock);
static void hairobb__pool_publish(struct hairobb__pool *pool, size_t task_count);

/* A task for range r; with a pool, its threads may start it at once (the
   list grows under the pool's lock, which they copy tasks out under). */
static uint64_t hairobb__add_task(hairobb__builder *b, const hairobb__range *r, unsigned depth, hairobb__tries tries)
{
    hairobb__task task, *grown = NULL;
    size_t capacity = b->task_capacity, index;
    if (b->task_count == b->task_capacity) {
        capacity = b->task_capacity ? 2 * b->task_capacity : 64;
        grown = HAIROBB__CAST(hairobb__task *, HAIROBB_MALLOC(capacity * sizeof *grown, b->user));
        if (!grown) { b->error = HAIROBB_ERROR_OUT_OF_MEMORY; return HAIROBB__REF_EMPTY; }
    }
    memset(&task, 0, sizeof task);
    task.range = *r;
    task.depth = depth;
    task.tries = tries;
    if (b->pool) hairobb__pool_lock(b->pool, 1);
    if (grown) {
        if (b->task_count) memcpy(grown, b->tasks, b->task_count * sizeof *grown);
        if (b->tasks) HAIROBB_FREE(b->tasks, b->user);
        b->tasks = grown;
        b->task_capacity = capacity;
    }
    index = b->task_count++;
    b->tasks[index] = task;
    if (b->pool) {
        hairobb__pool_publish(b->pool, b->task_count);
        hairobb__pool_lock(b->pool, 0);
    }
    return ((uint64_t)index << 4) | HAIROBB__REF_TASK;
}

/* hair_space: see hairobb__find_split */
static uint64_t hairobb__build_range(hairobb__builder *b, const hairobb__range *r, unsigned depth, hairobb__tries tries,
                                     const float *hair_space)
{
    hairobb__split split;
    size_t n = r->end - r->begin;
    if (n == 1) return hairobb__make_leaf(b, r, depth);
    if (n <= b->task_limit) return hairobb__add_task(b, r, depth, tries);
    hairobb__find_split(b, r, depth, tries.enabled, hair_space, &split);
    if (b->task_limit) {
        /* the top, on the calling thread: its own progress, and a cancel acts here too */
        b->top_done += n;
        hairobb__report_progress(b);
    }
    if (!hairobb__at_top(b, n)) hairobb__update_tries(&tries, &split);
    if (n <= b->max_leaf && hairobb__leaf_cost(n, split.parent_area) <= split.cost)
        return hairobb__make_leaf(b, r, depth);
    return hairobb__build_node(b, r, depth, &split, tries);
}

/* ------------------------------------------------------------------------ */
/* >>tasks  Builder: tasks on threads                                       */
/* ------------------------------------------------------------------------ */
/* References of the largest subtree built (or refitted) as one task: about
   HAIROBB__TASKS of them, of at least HAIROBB__TASK_MIN references; from
   the input alone, so any thread count builds the same tree. */
static size_t hairobb__task_limit(size_t references)
{
    return references / HAIROBB__TASKS > HAIROBB__TASK_MIN ? references / HAIROBB__TASKS : HAIROBB__TASK_MIN;
}

/* Positions the frame boxes hold for a builder over `positions` of them: the
   most a range binned in a frame spans. Above the tasks a mixed tree bins
   ranges of at most task_limit references in hair space
   (hairobb__find_split), an AABB tree none. */
static size_t hairobb__frame_capacity(const hairobb__builder *b, size_t positions)
{
    if (b->policy == HAIROBB_NODES_AABB_ONLY) return 0;
    if (b->policy == HAIROBB_NODES_MIXED && b->task_limit && positions > b->task_limit) return b->task_limit;
    return positions;
}

/* A task's segments in Bezier form, in memory of its own in the order of
   its positions: a large build's tasks then read points from a block that
   stays in cache (from the caller's arrays, a cache miss a box at 10M
   segments), and other bases are converted once. The positions hold
   local ids until their leaf is made (hairobb__make_leaf maps them back).
   block: 16 floats, an index and a segment id a reference. */
static void hairobb__copy_task_points(hairobb__builder *local, const hairobb__range *r, void *block)
{
    size_t count = r->end - r->begin, k;
    float *points = HAIROBB__CAST(float *, block), scratch[16];
    uint32_t *indices = HAIROBB__CAST(uint32_t *, HAIROBB__CAST(void *, points + 16 * count)), *segments = indices + count;
    for (k = 0; k < count; ++k) {
        uint32_t id = local->ids[r->begin + k];
        hairobb__prefetch_points(local, r->begin + k, r->end);
        memcpy(points + 16 * k, hairobb__builder_points(local, local->vertices, id, scratch), sizeof scratch);
        indices[k] = (uint32_t)(4 * k);
        segments[k] = id;
        local->ids[r->begin + k] = (uint32_t)k;
    }
    local->vertices = points;
    local->indices = indices;
    local->basis = HAIROBB_BASIS_BEZIER;
    local->tangents = NULL;
    local->segment_of = segments;
}

/* A pool thread's memory for its tasks' frame boxes and points, kept from
   one task to the next where a task needs HAIROBB__KEPT_BYTES or more:
   malloc maps blocks that large afresh each time, and a page fault costs
   microseconds (12 on this project's VMs). Smaller blocks come and go
   with their task (malloc reuses them), so that builds of up to millions
   of segments allocate alike on any thread count. */
typedef struct hairobb__task_memory {
    void *block;
    size_t bytes;
} hairobb__task_memory;
#define HAIROBB__KEPT_BYTES ((size_t)32 << 20)

/* Node bytes a reference takes, a little over what compressed nodes take
   on the bench's scenes: a task's first node block, so that it seldom
   grows by a copy. */
#define HAIROBB__NODE_BYTES_GUESS 36

/* memory: the thread's (NULL: the task's own, freed at its end). */
static void hairobb__run_task(const hairobb__builder *b, hairobb__task *task, hairobb__task_memory *memory)
{
    hairobb__task_memory own = {NULL, 0};
    hairobb__builder local = *b;
    size_t count = task->range.end - task->range.begin, frame_bytes, copy_bytes, bytes;
    const size_t copy_each = 16 * sizeof(float) + 2 * sizeof(uint32_t);
    local.node_allocation = local.nodes = NULL;
    local.node_bytes = local.node_capacity = 0;
    memset(&local.stats, 0, sizeof local.stats);
    local.error = HAIROBB_OK;
    local.task_limit = 0;           /* no tasks within a task; no progress calls */
    local.tasks = NULL;
    local.pool = NULL;
    local.task_count = local.task_capacity = 0;
    local.frame_capacity = hairobb__frame_capacity(&local, task->range.cap - task->range.begin);
    local.frame_boxes = NULL;
    local.node_reserve = count < (size_t)-1 / 4 / HAIROBB__NODE_BYTES_GUESS ? count * HAIROBB__NODE_BYTES_GUESS : 0;
    /* the points' copy (at the block's alignment; moving hair reads the
       steps' arrays, and indices of 4 k must fit), then the frame boxes */
    frame_bytes = 6 * sizeof(float) * local.frame_capacity;
    copy_bytes = local.time_steps || count > 0xffffffffu / 4 || count > ((size_t)-1 - frame_bytes) / copy_each ? 0
                                                                                                           : count * copy_each;
    bytes = copy_bytes + frame_bytes;
    if (!memory || bytes < HAIROBB__KEPT_BYTES) memory = &own;
    if (bytes > memory->bytes) {
        if (memory->block) HAIROBB_FREE(memory->block, local.user);
        memory->block = hairobb__malloc_large(bytes, local.user);
        memory->bytes = memory->block ? bytes : 0;
        if (!memory->block) local.error = HAIROBB_ERROR_OUT_OF_MEMORY;
    }
    if (local.error == HAIROBB_OK) {
        if (copy_bytes) hairobb__copy_task_points(&local, &task->range, memory->block);
        if (local.frame_capacity)
            local.frame_boxes = HAIROBB__CAST(float *, HAIROBB__CAST(void *, HAIROBB__CAST(unsigned char *, memory->block) + copy_bytes));
        task->root = hairobb__build_range(&local, &task->range, task->depth, task->tries, NULL);
    }
    if (own.block) HAIROBB_FREE(own.block, local.user);
    /* a block much larger than its nodes: copied into one of their size */
    if (local.error == HAIROBB_OK && local.node_bytes < local.node_capacity - local.node_capacity / 8) {
        unsigned char *exact = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(local.node_bytes, local.user));
        if (!exact) {
            local.error = HAIROBB_ERROR_OUT_OF_MEMORY;
        } else {
            memcpy(exact, local.nodes, local.node_bytes);
            HAIROBB_FREE(local.node_allocation, local.user);
            local.node_allocation = local.nodes = exact;
        }
    }
    task->node_allocation = local.node_allocation;
    task->nodes = local.nodes;
    task->node_bytes = local.node_bytes;
    task->stats = local.stats;
    task->error = local.error;
    task->ran = 1;
}

/* Tasks are handed out in order; the calling thread reports progress and
   turns a cancel into a stop for every thread. A build's top starts the
   threads before it splits (hairobb__pool_start) and adds its tasks as it
   makes them, so they run while it works on; the calling thread joins in
   when the top is done (hairobb__pool_finish). */
typedef struct hairobb__pool {
    size_t task_count;                /* run(context, k) for each k < task_count */
    hairobb_task_fn run;
    void *context;
    hairobb__builder *b;              /* a build's calling thread's (progress, cancels); NULL: a refit */
    hairobb__builder shared;          /* what every task starts from; never written while threads run */
    size_t next_task, positions_done;
    int stop;
    int adding;                       /* more tasks may come: idle threads wait for them */
    int locking;                      /* the lock and the signal exist (threads were started) */
    /* the top's parts (hairobb__top_parts), which idle threads take before tasks */
    hairobb_task_fn job;
    void *job_context;
    size_t job_parts, job_next, job_left;
#if HAIROBB__THREADS
    hairobb__mutex lock;
    hairobb__cond added;              /* a task or a part came, the adding ended, or a stop */
    hairobb__cond job_done;           /* the last part of the job ended */
    hairobb__thread workers[255];
    unsigned started;
#endif
} hairobb__pool;

static void hairobb__pool_lock(hairobb__pool *pool, int lock)
{
#if HAIROBB__THREADS
    if (!pool->locking) return;
    if (lock) hairobb__mutex_lock(&pool->lock); else hairobb__mutex_unlock(&pool->lock);
#else
    (void)pool; (void)lock;
#endif
}

/* Under the lock: tasks [0, task_count) may run. */
static void hairobb__pool_publish(hairobb__pool *pool, size_t task_count)
{
    pool->task_count = task_count;
#if HAIROBB__THREADS
    if (pool->locking) hairobb__cond_signal(&pool->added);
#endif
}

static void hairobb__run_listed_task(hairobb__pool *p, unsigned index, hairobb__task_memory *memory);

static void hairobb__work(hairobb__pool *pool, int calling_thread)
{
    hairobb__builder *b = pool->b;
    hairobb__task_memory memory = {NULL, 0};
    for (;;) {
        size_t k, done;
        int run;
        hairobb__pool_lock(pool, 1);
#if HAIROBB__THREADS
        while (pool->adding && !pool->stop && pool->next_task >= pool->task_count && !(pool->job && pool->job_next < pool->job_parts))
            hairobb__cond_wait(&pool->added, &pool->lock);
        if (pool->job && pool->job_next < pool->job_parts) {
            hairobb_task_fn job = pool->job;
            void *job_context = pool->job_context;
            unsigned part = (unsigned)pool->job_next++;
            hairobb__pool_lock(pool, 0);
            job(job_context, part);
            hairobb__pool_lock(pool, 1);
            if (--pool->job_left == 0) hairobb__cond_signal(&pool->job_done);
            hairobb__pool_lock(pool, 0);
            continue;
        }
#endif
        k = pool->next_task;
        run = !pool->stop && k < pool->task_count;
        if (run) pool->next_task++;
        hairobb__pool_lock(pool, 0);
        if (!run) break;
        if (!b) {
            pool->run(pool->context, (unsigned)k);
            continue;
        }
        hairobb__run_listed_task(pool, (unsigned)k, &memory);
        hairobb__pool_lock(pool, 1);
        pool->positions_done += b->tasks[k].range.cap - b->tasks[k].range.begin;
        done = pool->positions_done;
        if (b->tasks[k].error != HAIROBB_OK) pool->stop = 1;
        hairobb__pool_lock(pool, 0);
        if (calling_thread) {
            hairobb__finish_positions(b, done - b->positions_done);
            if (b->error != HAIROBB_OK) {
                hairobb__pool_lock(pool, 1);
                pool->stop = 1;
                hairobb__pool_lock(pool, 0);
            }
        }
    }
    if (memory.block) HAIROBB_FREE(memory.block, b->user);
}

#if HAIROBB__THREADS
HAIROBB__THREAD_FN(hairobb__worker, pool)
{
    hairobb__work(HAIROBB__CAST(hairobb__pool *, pool), 0);
    HAIROBB__THREAD_END;
}
#endif

/* Up to `threads` - 1 threads beside the calling one (0: one per core), at
   most one per task of most_tasks; none where threads are not built in. */
static void hairobb__pool_start(hairobb__pool *pool, unsigned threads, size_t most_tasks)
{
#if HAIROBB__THREADS
    if (threads == 0) {
        long cores = hairobb__core_count();
        threads = cores < 1 ? 1u : cores > 256 ? 256u : (unsigned)cores;
    }
    if (threads > most_tasks) threads = most_tasks ? (unsigned)most_tasks : 1u;
    if (threads < 2 || hairobb__mutex_init(&pool->lock) != 0) return;
    if (hairobb__cond_init(&pool->added) != 0) {
        hairobb__mutex_destroy(&pool->lock);
        return;
    }
    if (hairobb__cond_init(&pool->job_done) != 0) {
        hairobb__cond_destroy(&pool->added);
        hairobb__mutex_destroy(&pool->lock);
        return;
    }
    pool->locking = 1;
    /* fewer threads than asked, if some would not start */
    while (pool->started < threads - 1 && hairobb__thread_start(&pool->workers[pool->started], hairobb__worker, pool) == 0)
        ++pool->started;
#else
    (void)pool; (void)threads; (void)most_tasks;
#endif
}

/* No more tasks come; the calling thread runs tasks with the others until
   none is left, then they end. */
static void hairobb__pool_finish(hairobb__pool *pool)
{
#if HAIROBB__THREADS
    unsigned i;
    hairobb__pool_lock(pool, 1);
    pool->adding = 0;
    if (pool->locking) hairobb__cond_broadcast(&pool->added);
    hairobb__pool_lock(pool, 0);
    hairobb__work(pool, 1);
    for (i = 0; i < pool->started; ++i) hairobb__thread_join(pool->workers[i]);
    if (pool->locking) {
        hairobb__cond_destroy(&pool->job_done);
        hairobb__cond_destroy(&pool->added);
        hairobb__mutex_destroy(&pool->lock);
    }
    pool->locking = 0;
    pool->started = 0;
#else
    pool->adding = 0;
    hairobb__work(pool, 1);
#endif
}

/* One task, from the pool or a user's parallel_for: run on a copy, as the
   top may move the task list meanwhile. */
static void hairobb__run_listed_task(hairobb__pool *p, unsigned index, hairobb__task_memory *memory)
{
    hairobb__task task;
    int listed;
    hairobb__pool_lock(p, 1);
    listed = index < p->b->task_count;
    if (listed) task = p->b->tasks[index];
    else memset(&task, 0, sizeof task);
    hairobb__pool_lock(p, 0);
    if (!listed) return;
    hairobb__run_task(&p->shared, &task, memory);
    hairobb__pool_lock(p, 1);
    p->b->tasks[index] = task;
    hairobb__pool_lock(p, 0);
}

/* A user's parallel_for: each task with memory of its own. */
static void hairobb__run_task_at(void *pool, unsigned index)
{
    hairobb__run_listed_task(HAIROBB__CAST(hairobb__pool *, pool), index, NULL);
}

/* The tasks through a user's parallel_for, then their progress at once. */
static void hairobb__run_tasks_for(hairobb__pool *pool, hairobb_parallel_for_fn parallel_for, void *user)
{
    hairobb__builder *b = pool->b;
    size_t k, positions = 0;
    parallel_for(user, (unsigned)b->task_count, hairobb__run_task_at, pool);
    for (k = 0; k < b->task_count; ++k) {
        if (!b->tasks[k].ran) { b->error = HAIROBB_ERROR_INVALID_ARGUMENT; return; }
        positions += b->tasks[k].range.cap - b->tasks[k].range.begin;
    }
    hairobb__finish_positions(b, positions);
}

/* The tasks of a refit (or of a build without a started pool) on up to
   `threads` threads, the calling thread among them. */
static void hairobb__run_tasks_on_threads(hairobb__pool *pool, unsigned threads)
{
    hairobb__pool_start(pool, threads, pool->task_count);
    hairobb__pool_finish(pool);
}

/* run(context, k) for each part k < parts: on the user's parallel_for, or
   on up to `threads` threads with the calling one. */
static void hairobb__run_parts(unsigned threads, hairobb_parallel_for_fn parallel_for, void *parallel_for_user,
                               size_t parts, hairobb_task_fn run, void *context)
{
    hairobb__pool pool;
    size_t k;
    if (parts < 2) {
        for (k = 0; k < parts; ++k) run(context, (unsigned)k);
        return;
    }
    if (parallel_for) {
        parallel_for(parallel_for_user, (unsigned)parts, run, context);
        return;
    }
    memset(&pool, 0, sizeof pool);
    pool.run = run;
    pool.context = context;
    pool.task_count = parts;
    hairobb__run_tasks_on_threads(&pool, threads);
}

/* run(context, k) for each part k < parts of a range at the top: on the
   calling thread, and on the pool's threads that are between tasks. */
static void hairobb__top_parts(const hairobb__builder *b, size_t parts, hairobb_task_fn run, void *context)
{
    hairobb__pool *pool = b->pool;
    size_t k;
#if HAIROBB__THREADS
    if (pool && pool->locking && parts > 1) {
        hairobb__mutex_lock(&pool->lock);
        pool->job = run;
        pool->job_context = context;
        pool->job_parts = parts;
        pool->job_next = 0;
        pool->job_left = parts;
        hairobb__cond_broadcast(&pool->added);
        while (pool->job_next < pool->job_parts) {
            k = pool->job_next++;
            hairobb__mutex_unlock(&pool->lock);
            run(context, (unsigned)k);
            hairobb__mutex_lock(&pool->lock);
            --pool->job_left;
        }
        while (pool->job_left) hairobb__cond_wait(&pool->job_done, &pool->lock);
        pool->job = NULL;
        hairobb__mutex_unlock(&pool->lock);
        return;
    }
#else
    (void)pool;
#endif
    for (k = 0; k < parts; ++k) run(context, (unsigned)k);
}

/* ------------------------------------------------------------------------ */
/* >>passes  Builder: the passes over every segment, and the build's steps  */
/* ------------------------------------------------------------------------ */
/* The build's first pass: every position holds its segment whole, with its
   world box; each part's bounds of the boxes (of every step's, for moving
   hair whose SAH boxes are at mid-time), merged into the BVH's. */
typedef struct hairobb__world_pass {
    hairobb__builder *b;
    size_t segment_count, parts;
    float bounds[HAIROBB__PARTS][6];
    int ran[HAIROBB__PARTS];          /* a user's parallel_for must run each part */
} hairobb__world_pass;

static void hairobb__world_part(void *context, unsigned k)
{
    hairobb__world_pass *pass = HAIROBB__CAST(hairobb__world_pass *, context);
    hairobb__builder *b = pass->b;
    float identity[9], *lower = pass->bounds[k], *upper = lower + 3;
    hairobb__frame_prep world;
    size_t i, begin, end;
    hairobb__identity_frame(identity);
    hairobb__prepare_frame(identity, &world);
    hairobb__part_items(pass->segment_count, pass->parts, k, &begin, &end);
    hairobb__box_empty(lower, upper);
    for (i = begin; i < end; ++i) {
        float *box = b->world_boxes + 6 * i;
        b->ids[i] = (uint32_t)i;
        if (b->ranges) { b->ranges[2 * i] = 0.0f; b->ranges[2 * i + 1] = 1.0f; }
        hairobb__ref_box(b, i, &world, NULL, NULL, box, box + 3);
        if (b->sah_mid_time) {   /* the boxes are at mid-time; the bounds hold every step */
            hairobb__b4 lo, hi;
            float step_lower[3], step_upper[3];
            hairobb__ref_box_union(b, i, &world, NULL, NULL, &lo, &hi);
            hairobb__b4_store3(step_lower, lo);
            hairobb__b4_store3(step_upper, hi);
            hairobb__box_grow(lower, upper, step_lower, step_upper);
        } else {
            hairobb__box_grow(lower, upper, box, box + 3);
        }
    }
    pass->ran[k] = 1;
}

/* Returns 0 if a user's parallel_for left a part unrun. */
static int hairobb__world_boxes(hairobb__builder *b, size_t segment_count, unsigned threads,
                                hairobb_parallel_for_fn parallel_for, void *parallel_for_user, float lower[3], float upper[3])
{
    hairobb__world_pass pass;
    size_t k;
    pass.b = b;
    pass.segment_count = segment_count;
    pass.parts = hairobb__part_count(segment_count);
    memset(pass.ran, 0, sizeof pass.ran);
    hairobb__run_parts(threads, parallel_for, parallel_for_user, pass.parts, hairobb__world_part, &pass);
    hairobb__box_empty(lower, upper);
    for (k = 0; k < pass.parts; ++k) {
        if (!pass.ran[k]) return 0;
        hairobb__box_grow(lower, upper, pass.bounds[k], pass.bounds[k] + 3);
    }
    return 1;
}

/* The build's threads, before its top: they take its tasks as it adds them
   (not with a user's parallel_for, which takes a count of tasks). */
static void hairobb__start_build_pool(hairobb__builder *b, hairobb__pool *pool, size_t segment_count, unsigned threads,
                                      hairobb_parallel_for_fn parallel_for)
{
    memset(pool, 0, sizeof *pool);
    pool->run = hairobb__run_task_at;
    pool->context = pool;
    pool->b = b;
    if (parallel_for || segment_count <= b->task_limit) return;   /* no top: the root is the one task */
    pool->shared = *b;
    pool->adding = 1;
    hairobb__pool_start(pool, threads, (size_t)-1);
    if (pool->locking) b->pool = pool;
    else pool->adding = 0;
}

/* Runs every task; the first failure, or a cancel, is left in b->error.
   Called after the top, whether it failed or not: the pool's threads end. */
static void hairobb__run_tasks(hairobb__builder *b, hairobb__pool *pool, unsigned threads,
                               hairobb_parallel_for_fn parallel_for, void *parallel_for_user)
{
    size_t k;
    if (b->pool) {
        hairobb__pool_lock(pool, 1);
        pool->positions_done += b->positions_done;    /* the top's leaves, with the tasks done so far */
        if (b->error != HAIROBB_OK) pool->stop = 1;
        hairobb__pool_lock(pool, 0);
        hairobb__pool_finish(pool);
        b->pool = NULL;
    } else {
        if (b->error != HAIROBB_OK) return;
        pool->task_count = b->task_count;
        pool->positions_done = b->positions_done;    /* leaves of the top part */
        pool->shared = *b;
        if (parallel_for && b->task_count)
            hairobb__run_tasks_for(pool, parallel_for, parallel_for_user);
        else
            hairobb__run_tasks_on_threads(pool, threads);
    }
    if (b->error != HAIROBB_OK) return;
    for (k = 0; k < b->task_count && b->error == HAIROBB_OK; ++k) b->error = b->tasks[k].error;
    if (b->error == HAIROBB_OK && pool->stop) b->error = HAIROBB_ERROR_CANCELLED;
}

typedef struct hairobb__gather {
    hairobb__builder *b;
    unsigned char *nodes;
} hairobb__gather;

/* Task k's nodes copied to where they go, its block freed. */
static void hairobb__gather_task(void *context, unsigned k)
{
    const hairobb__gather *g = HAIROBB__CAST(const hairobb__gather *, context);
    hairobb__task *task = &g->b->tasks[k];
    if (task->node_bytes) memcpy(g->nodes + task->node_delta, task->nodes, task->node_bytes);
    if (task->node_allocation) HAIROBB_FREE(task->node_allocation, g->b->user);
    task->node_allocation = task->nodes = NULL;
    task->finished = 1;
}

/* The BVH's node memory, of the nodes' size: the top's nodes, then each
   task's, in task order, copied in parallel; the tasks' statistics
   summed. A user's parallel_for that skips a task: INVALID_ARGUMENT. */
static void hairobb__gather_tasks(hairobb__builder *b, hairobb_bvh *bvh, unsigned threads,
                                  hairobb_parallel_for_fn parallel_for, void *parallel_for_user)
{
    hairobb__gather g;
    size_t k, bytes = b->node_bytes;
    for (k = 0; k < b->task_count; ++k) {
        b->tasks[k].node_delta = bytes;
        b->tasks[k].finished = 0;
        bytes += b->tasks[k].node_bytes;
    }
    if (bytes) {
        unsigned char *allocation = HAIROBB__CAST(unsigned char *, hairobb__malloc_large(bytes + 64, b->user));
        if (!allocation) { b->error = HAIROBB_ERROR_OUT_OF_MEMORY; return; }
        bvh->node_allocation = allocation;
        bvh->nodes = hairobb__align64(allocation);
        bvh->node_bytes = bytes;
        if (b->node_bytes) memcpy(bvh->nodes, b->nodes, b->node_bytes);
    }
    if (b->node_allocation) HAIROBB_FREE(b->node_allocation, b->user);
    b->node_allocation = b->nodes = NULL;
    b->node_bytes = b->node_capacity = 0;
    g.b = b;
    g.nodes = bvh->nodes;
    hairobb__run_parts(threads, parallel_for, parallel_for_user, b->task_count, hairobb__gather_task, &g);
    for (k = 0; k < b->task_count; ++k) {
        const hairobb__task *task = &b->tasks[k];
        unsigned depth = task->stats.max_depth;
        if (!task->finished) b->error = HAIROBB_ERROR_INVALID_ARGUMENT;
        b->stats.aabb_nodes += task->stats.aabb_nodes;
        b->stats.obb_nodes += task->stats.obb_nodes;
        b->stats.leaves += task->stats.leaves;
        b->stats.leaf_references += task->stats.leaf_references;
        if (depth > b->stats.max_depth) b->stats.max_depth = depth;
    }
}

static void hairobb__free_tasks(hairobb__builder *b)
{
    size_t k;
    for (k = 0; k < b->task_count; ++k)
        if (b->tasks[k].node_allocation) HAIROBB_FREE(b->tasks[k].node_allocation, b->user);
    if (b->tasks) HAIROBB_FREE(b->tasks, b->user);
    b->tasks = NULL;
    b->task_count = b->task_capacity = 0;
}

/* The last pass, in tree order: task references become their subtrees, node
   offsets move by where the subtree's nodes went, and leaves get their
   segment ids copied out of the positions they named. With tasks_later a
   task's reference stays, and the task notes where it is (slot) and where
   its leaves' ids start: hairobb__finish_task does the rest, in parallel,
   with the same result. */
typedef struct hairobb__finish {
    const hairobb__builder *b;
    unsigned char *nodes;
    uint32_t *leaf_prims;
    float *leaf_ranges;
    int tasks_later;
} hairobb__finish;

/* slot: where the reference is (in nodes, or the root's copy) */
static void hairobb__finish_tree(const hairobb__finish *f, unsigned char *slot, size_t node_delta, size_t *leaf_count)
{
    uint64_t ref;
    unsigned type;
    size_t child_offset;
    int i;
    memcpy(&ref, slot, sizeof ref);
    type = HAIROBB__REF_TYPE(ref);
    if (type == HAIROBB__REF_TASK) {
        hairobb__task *task = &f->b->tasks[ref >> 4];
        if (f->tasks_later) {
            task->slot = slot;
            task->leaf_first = *leaf_count;
            *leaf_count += task->stats.leaf_references;
            return;
        }
        ref = task->root;
        node_delta = task->node_delta;
        type = HAIROBB__REF_TYPE(ref);
    }
    if (type == HAIROBB__REF_EMPTY) return;
    if (type == HAIROBB__REF_LEAF) {
        size_t start = (size_t)(ref >> 8), count = (size_t)((ref >> 4) & 15u);
        memcpy(f->leaf_prims + *leaf_count, f->b->ids + start, count * sizeof(uint32_t));
        if (f->leaf_ranges) memcpy(f->leaf_ranges + 2 * *leaf_count, f->b->ranges + 2 * start, 2 * count * sizeof(float));
        ref = ((uint64_t)*leaf_count << 8) | ((uint64_t)count << 4) | HAIROBB__REF_LEAF;
        memcpy(slot, &ref, sizeof ref);
        *leaf_count += count;
        return;
    }
    ref += node_delta;
    memcpy(slot, &ref, sizeof ref);
    child_offset = HAIROBB__NODE_OFFSET(ref) + hairobb__node_size(type) - HAIROBB__W * sizeof(uint64_t);
    for (i = 0; i < HAIROBB__W; ++i) hairobb__finish_tree(f, f->nodes + child_offset + (size_t)i * sizeof ref, node_delta, leaf_count);
}

/* Task k's part of the last pass: its subtree finished. */
static void hairobb__finish_task(void *context, unsigned k)
{
    const hairobb__finish *f = HAIROBB__CAST(const hairobb__finish *, context);
    hairobb__finish own = *f;
    hairobb__task *task = &f->b->tasks[k];
    size_t leaf_count = task->leaf_first;
    own.tasks_later = 0;
    if (task->slot) hairobb__finish_tree(&own, task->slot, 0, &leaf_count);
    task->finished = leaf_count == task->leaf_first + task->stats.leaf_references;
}

/* The last pass over the whole tree: the top's part on the calling thread,
   the tasks' in parallel. Returns 0 if a user's parallel_for left a task's
   part unrun. */
static int hairobb__finish_build(hairobb__builder *b, hairobb_bvh *bvh, unsigned threads,
                                 hairobb_parallel_for_fn parallel_for, void *parallel_for_user)
{
    hairobb__finish f;
    unsigned char root[sizeof(uint64_t)];
    size_t k;
    f.b = b;
    f.nodes = bvh->nodes;
    f.leaf_prims = bvh->leaf_prims;
    f.leaf_ranges = bvh->leaf_ranges;
    f.tasks_later = 1;
    bvh->leaf_prim_count = 0;
    memcpy(root, &bvh->root, sizeof root);
    for (k = 0; k < b->task_count; ++k) {
        b->tasks[k].slot = NULL;
        b->tasks[k].finished = 0;
    }
    hairobb__finish_tree(&f, root, 0, &bvh->leaf_prim_count);
    hairobb__run_parts(threads, parallel_for, parallel_for_user, b->task_count, hairobb__finish_task, &f);
    memcpy(&bvh->root, root, sizeof root);
    for (k = 0; k < b->task_count; ++k)
        if (!b->tasks[k].finished) return 0;
    return 1;
}

static void hairobb__setup_pieces(hairobb_bvh *bvh, int pieces)
{
    int chunk, lane, end;
    bvh->pieces = pieces;
    bvh->piece_chunks = (pieces + 7) / 8;
    for (chunk = 0; chunk < 2; ++chunk) {
        int first = 8 * chunk;
        int real = pieces - first < 0 ? 0 : pieces - first > 8 ? 8 : pieces - first;
        bvh->chunk_valid[chunk] = (1u << real) - 1u;
        for (lane = 0; lane < 8; ++lane) {
            /* lanes past the last piece repeat it; they are masked out */
            int k = first + lane < pieces ? first + lane : pieces - 1;
            for (end = 0; end < 2; ++end) {
                float u = (float)(k + end) / (float)pieces, s = 1.0f - u;
                bvh->piece_weights[chunk][end][0][lane] = s * s * s;
                bvh->piece_weights[chunk][end][1][lane] = 3.0f * u * s * s;
                bvh->piece_weights[chunk][end][2][lane] = 3.0f * u * u * s;
                bvh->piece_weights[chunk][end][3][lane] = u * u * u;
            }
        }
    }
}

/* Bytes of the leaves' segment ids, and of the clipped parts' ranges. */
static size_t hairobb__leaf_bytes(const hairobb_bvh *bvh)
{
    return (sizeof(uint32_t) + (bvh->leaf_ranges ? 2 * sizeof(float) : 0)) * bvh->leaf_prim_count;
}

/* The settings a BVH traces with, as hairobb_build and hairobb_load fill
   them in: the tree's, and the options given for tracing and refitting
   (a refit runs on the build's, or the load's, threads). */
static void hairobb__set_settings(hairobb_bvh *bvh, const hairobb_build_options *opt, hairobb_simd simd,
                                  const hairobb__tree_settings *tree)
{
    bvh->precision = tree->precision;
    bvh->shape = tree->shape;
    bvh->end_caps = tree->end_caps;
    bvh->cull_back_faces = tree->cull_back_faces;
    bvh->policy = tree->policy;
    bvh->obb_layout = tree->obb_layout;
    bvh->max_leaf_size = tree->max_leaf_size;
    hairobb__setup_pieces(bvh, (int)tree->pieces);
    bvh->simd = simd;
    bvh->hit_filter = opt->hit_filter;
    bvh->hit_filter_user = opt->hit_filter_user;
    bvh->occluded_filter = opt->occluded_filter ? opt->occluded_filter : opt->hit_filter;
    bvh->occluded_filter_user = opt->occluded_filter ? opt->occluded_filter_user : opt->hit_filter_user;
    bvh->threads = opt->threads;
    bvh->parallel_for = opt->parallel_for;
    bvh->parallel_for_user = opt->parallel_for_user;
}

/* The tree's counts (a build's, or a load's walk), with its bytes. */
static void hairobb__set_stats(hairobb_bvh *bvh, const hairobb_stats *stats)
{
    bvh->stats = *stats;
    bvh->stats.node_bytes = bvh->node_bytes;
    bvh->stats.leaf_bytes = hairobb__leaf_bytes(bvh);
}

static double hairobb__sah_cost(const hairobb_bvh *bvh);

/* The builder's settings from resolved options, and the memory it holds
   throughout: 28 bytes a position (36 with spatial splits) and the frame
   boxes of the top's ranges (a task has its own). 0: out of memory (what
   was allocated is freed by hairobb__builder_free). */
static int hairobb__builder_start(hairobb__builder *b, const hairobb_build_options *opt, size_t segment_count,
                                  size_t extra, unsigned steps)
{
    size_t halvings = 0, size;
    b->time_steps = steps;
    b->time_vertices = opt->time_vertices;
    b->sah_mid_time = steps && (opt->obb_layout == HAIROBB_OBB_COMPRESSED || opt->obb_layout == HAIROBB_OBB_COMPRESSED_PER_CHILD);
    b->user = opt->allocator_user;
    b->policy = opt->nodes;
    b->obb_layout = opt->obb_layout;
    b->max_leaf = opt->max_leaf_size;
    b->candidates = opt->hair_space_candidates;
    b->progress = opt->progress;
    b->progress_user = opt->progress_user;
    b->capacity = segment_count + extra;
    /* the top of the tree here, subtrees of at most task_limit references as
       tasks; the limit depends on the input alone (same tree on any thread count) */
    b->task_limit = hairobb__task_limit(segment_count);
    /* each reference is binned about once per halving from the root to task_limit */
    for (size = b->capacity; size > b->task_limit; size /= 2) ++halvings;
    b->top_work = b->capacity * halvings;
    b->frame_capacity = hairobb__frame_capacity(b, b->capacity);
    b->ids = HAIROBB__CAST(uint32_t *, hairobb__malloc_large(sizeof(uint32_t) * b->capacity, b->user));
    if (opt->spatial_splits == HAIROBB_ON)
        b->ranges = HAIROBB__CAST(float *, hairobb__malloc_large(2 * sizeof(float) * b->capacity, b->user));
    b->world_boxes = HAIROBB__CAST(float *, hairobb__malloc_large(6 * sizeof(float) * b->capacity, b->user));
    if (b->frame_capacity)
        b->frame_boxes = HAIROBB__CAST(float *, hairobb__malloc_large(6 * sizeof(float) * b->frame_capacity, b->user));
    return b->ids && (opt->spatial_splits != HAIROBB_ON || b->ranges) && b->world_boxes && (!b->frame_capacity || b->frame_boxes);
}

/* Everything a builder still holds (after a failure, or its last pass). */
static void hairobb__builder_free(hairobb__builder *b)
{
    if (b->node_allocation) HAIROBB_FREE(b->node_allocation, b->user);
    if (b->ids) HAIROBB_FREE(b->ids, b->user);
    if (b->ranges) HAIROBB_FREE(b->ranges, b->user);
    if (b->world_boxes) HAIROBB_FREE(b->world_boxes, b->user);
    if (b->frame_boxes) HAIROBB_FREE(b->frame_boxes, b->user);
    hairobb__free_tasks(b);
    b->node_allocation = NULL;
    b->ids = NULL;
    b->ranges = b->world_boxes = b->frame_boxes = NULL;
}

/* The tree over the builder's segments: the first pass, the top on the
   calling thread with the tasks on threads, the gather of their nodes into
   the BVH's block. The first failure is left in b->error. */
static void hairobb__build_tree(hairobb__builder *b, hairobb_bvh *bvh, const hairobb_build_options *opt, size_t segment_count)
{
    hairobb__pool pool;
    hairobb__range root;
    hairobb__tries tries;
    if (!hairobb__world_boxes(b, segment_count, opt->threads, opt->parallel_for, opt->parallel_for_user, bvh->lower, bvh->upper)) {
        b->error = HAIROBB_ERROR_INVALID_ARGUMENT;
        return;
    }
    root.begin = 0; root.end = segment_count; root.cap = b->capacity;
    memset(&tries, 0, sizeof tries);
    tries.enabled = HAIROBB__TRY_HAIR_SPACE | (opt->spatial_splits == HAIROBB_ON ? HAIROBB__TRY_SPATIAL : 0u) |
                    (opt->clustering == HAIROBB_ON ? HAIROBB__TRY_CLUSTER : 0u);
    hairobb__start_build_pool(b, &pool, segment_count, opt->threads, opt->parallel_for);
    bvh->root = hairobb__build_range(b, &root, 0, tries, NULL);
    if (b->frame_boxes) HAIROBB_FREE(b->frame_boxes, b->user);
    b->frame_boxes = NULL;
    hairobb__run_tasks(b, &pool, opt->threads, opt->parallel_for, opt->parallel_for_user);
    /* from here on only ids, for the leaves, and the u ranges of spatial
       splits, which the leaves keep for hairobb_refit */
    HAIROBB_FREE(b->world_boxes, b->user);
    b->world_boxes = NULL;
    if (b->error == HAIROBB_OK) hairobb__gather_tasks(b, bvh, opt->threads, opt->parallel_for, opt->parallel_for_user);
    if (b->error == HAIROBB_OK && b->progress && b->progress(b->progress_user, 1.0f)) b->error = HAIROBB_ERROR_CANCELLED;
}

/* The leaves' arrays, filled by the last pass: exactly what tracing needs
   (memory_bytes reports what stays). */
static hairobb_result hairobb__build_leaves(hairobb__builder *b, hairobb_bvh *bvh, const hairobb_build_options *opt,
                                            size_t segment_count)
{
    bvh->leaf_prims = HAIROBB__CAST(uint32_t *, hairobb__malloc_large(sizeof(uint32_t) * b->stats.leaf_references, b->user));
    if (!bvh->leaf_prims) return HAIROBB_ERROR_OUT_OF_MEMORY;
    if (opt->spatial_splits == HAIROBB_ON) {
        /* hairobb_refit bounds the clipped parts again: their u ranges stay, unless none was clipped */
        bvh->leaf_ranges = HAIROBB__CAST(float *, hairobb__malloc_large(2 * sizeof(float) * b->stats.leaf_references, b->user));
        if (!bvh->leaf_ranges) return HAIROBB_ERROR_OUT_OF_MEMORY;
    }
    if (!hairobb__finish_build(b, bvh, opt->threads, opt->parallel_for, opt->parallel_for_user)) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (bvh->leaf_ranges && bvh->leaf_prim_count == segment_count) {
        /* every segment once: none was clipped */
        HAIROBB_FREE(bvh->leaf_ranges, b->user);
        bvh->leaf_ranges = NULL;
    }
    return HAIROBB_OK;
}

/* The copy's bytes: 64 a leaf reference, 4 a segment (point_refs), and
   room to start on a 64-byte line. */
static size_t hairobb__copy_bytes(size_t leaf_references, size_t segment_count)
{
    return 16 * sizeof(float) * leaf_references + sizeof(uint32_t) * segment_count + 64;
}

/* The copy's tasks: consecutive ranges of the leaf references. */
#define HAIROBB__COPY_TASK 65536u   /* references a task, at least */
typedef struct hairobb__copy_job {
    hairobb_bvh *bvh;
    size_t per_task;
    unsigned char ran[HAIROBB__TASKS];
} hairobb__copy_job;

static void hairobb__copy_task(void *context, unsigned index)
{
    hairobb__copy_job *job = HAIROBB__CAST(hairobb__copy_job *, context);
    const hairobb_bvh *bvh = job->bvh;
    float *points = bvh->leaf_points;
    size_t i = (size_t)index * job->per_task, end = i + job->per_task;
    if (end > bvh->leaf_prim_count) end = bvh->leaf_prim_count;
    if (bvh->leaf_offsets) {
        for (; i < end; ++i) bvh->leaf_offsets[i] = bvh->indices[bvh->leaf_prims[i]];
        job->ran[index] = 1;
        return;
    }
    for (; i < end; ++i) {
        size_t at = 4 * (size_t)bvh->indices[bvh->leaf_prims[i]];
        if (bvh->point_basis == HAIROBB_BASIS_BEZIER)
            memcpy(points + 16 * i, bvh->vertices + at, 16 * sizeof(float));
        else
            hairobb__to_bezier(bvh->point_basis, bvh->vertices + at, bvh->tangents ? bvh->tangents + at : NULL, points + 16 * i);
    }
    job->ran[index] = 1;
}

/* The copy (bezier_copy ON, static hair): each leaf reference's Bezier
   control points in leaf order, read from the caller's arrays (other
   bases converted as the build read them: the same floats), so that a
   leaf's segments lie on consecutive 64-byte lines, and point_refs.
   hairobb_refit writes the points again into the same memory. Every
   segment has a reference in a built tree, and the loader checks a saved
   one for that. Without the copy, leaf_offsets instead (a refit leaves
   them: the indices stay). On the BVH's threads (or parallel_for):
   the caller's arrays are read in no order of memory. */
static hairobb_result hairobb__copy_points(hairobb_bvh *bvh)
{
    size_t refs = bvh->leaf_prim_count, i;
    unsigned tasks, k;
    hairobb__copy_job job;
    if (!bvh->copy_points) {
        if (bvh->leaf_offsets) return HAIROBB_OK;
        bvh->leaf_offsets = HAIROBB__CAST(uint32_t *, hairobb__malloc_large(sizeof(uint32_t) * refs, bvh->allocator_user));
        if (!bvh->leaf_offsets) return HAIROBB_ERROR_OUT_OF_MEMORY;
    } else if (!bvh->points_allocation) {
        unsigned char *block = HAIROBB__CAST(unsigned char *, hairobb__malloc_large(hairobb__copy_bytes(refs, bvh->segment_count),
                                                                                      bvh->allocator_user));
        if (!block) return HAIROBB_ERROR_OUT_OF_MEMORY;
        bvh->points_allocation = block;
        bvh->leaf_points = HAIROBB__CAST(float *, HAIROBB__CAST(void *, hairobb__align64(block)));
        bvh->point_refs = HAIROBB__CAST(uint32_t *, HAIROBB__CAST(void *, bvh->leaf_points + 16 * refs));
        memset(bvh->point_refs, 0xff, sizeof(uint32_t) * bvh->segment_count);
        for (i = refs; i-- > 0;) bvh->point_refs[bvh->leaf_prims[i]] = (uint32_t)i;   /* its first */
        for (i = 0; i < bvh->segment_count; ++i)
            if (bvh->point_refs[i] == 0xffffffffu) return HAIROBB_ERROR_INVALID_FILE;
    }
    memset(&job, 0, sizeof job);
    job.bvh = bvh;
    job.per_task = refs / HAIROBB__TASKS + 1;
    if (job.per_task < HAIROBB__COPY_TASK) job.per_task = HAIROBB__COPY_TASK;
    tasks = (unsigned)((refs + job.per_task - 1) / job.per_task);
    hairobb__run_parts(bvh->threads, bvh->parallel_for, bvh->parallel_for_user, tasks, hairobb__copy_task, &job);
    for (k = 0; k < tasks; ++k)
        if (!job.ran[k]) hairobb__copy_task(&job, k);   /* those a user's parallel_for skipped */
    return HAIROBB_OK;
}

/* ------------------------------------------------------------------------ */
/* >>build_api  Building: hairobb_build, hairobb_free, memory and stats     */
/* ------------------------------------------------------------------------ */
HAIROBB_DEF hairobb_result hairobb_build(const float *vertices, size_t vertex_count,
                             const uint32_t *indices, size_t segment_count,
                             const hairobb_build_options *options, hairobb_bvh **out)
{
    hairobb_build_options opt;
    hairobb__tree_settings tree;
    hairobb__builder b;
    hairobb_bvh *bvh;
    hairobb_result result;
    hairobb_simd simd;
    size_t extra;
    unsigned steps;

    if (out) *out = NULL;
    memset(&opt, 0, sizeof opt);   /* read below even where the options were refused */
    result = hairobb__resolve_options(options, HAIROBB__FOR_BUILD, &opt);
    if (!out || (!vertices && opt.time_steps < 2) || !indices || segment_count == 0) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (result == HAIROBB_OK) result = hairobb__choose_simd(opt.simd, &simd);
    if (result == HAIROBB_OK) result = hairobb__validate_hair(&opt, &vertices, vertex_count, indices, segment_count, &steps);
    if (result != HAIROBB_OK) return result;
    extra = opt.spatial_splits == HAIROBB_ON ? (size_t)((double)segment_count * opt.spatial_split_budget) : 0;
    if (segment_count > (size_t)-1 / 2 - extra || segment_count + extra > (size_t)-1 / (16 * sizeof(float) + 2 * sizeof(uint32_t)) ||
        segment_count + extra > (size_t)-1 / (6 * sizeof(float)) || segment_count + extra > 0xffffffffu)
        return HAIROBB_ERROR_TOO_LARGE;

    memset(&b, 0, sizeof b);
    bvh = HAIROBB__CAST(hairobb_bvh *, HAIROBB_MALLOC(sizeof *bvh, opt.allocator_user));
    if (bvh) {   /* the failure path frees it with hairobb_free */
        memset(bvh, 0, sizeof *bvh);
        bvh->allocator_user = opt.allocator_user;
    }
    b.error = HAIROBB_ERROR_OUT_OF_MEMORY;
    if (!hairobb__builder_start(&b, &opt, segment_count, extra, steps) || !bvh) goto failed;
    if (!hairobb__take_hair(bvh, &opt, vertices, vertex_count, indices, segment_count, steps)) goto failed;
    /* the builder reads the caller's points as tracing reads them without the copy */
    b.vertices = bvh->vertices;
    b.indices = bvh->indices;
    b.basis = bvh->point_basis;
    b.tangents = bvh->tangents;
    b.error = HAIROBB_OK;
    hairobb__build_tree(&b, bvh, &opt, segment_count);
    if (b.error == HAIROBB_OK) b.error = hairobb__build_leaves(&b, bvh, &opt, segment_count);
    if (b.error != HAIROBB_OK) goto failed;
    hairobb__builder_free(&b);
    hairobb__pad_box(bvh->lower, bvh->upper);
    tree.precision = opt.precision;
    tree.shape = opt.shape;
    tree.end_caps = opt.shape == HAIROBB_SHAPE_ROUND && opt.end_caps == HAIROBB_ON;
    tree.cull_back_faces = opt.shape == HAIROBB_SHAPE_ROUND && opt.back_faces == HAIROBB_OFF;
    tree.policy = opt.nodes;
    tree.obb_layout = opt.obb_layout;
    tree.max_leaf_size = opt.max_leaf_size;
    tree.pieces = opt.curve_pieces;
    hairobb__set_settings(bvh, &opt, simd, &tree);
    hairobb__set_stats(bvh, &b.stats);
    b.error = hairobb__copy_points(bvh);   /* on the threads set */
    if (b.error != HAIROBB_OK) goto failed;
    if (bvh->copy_points && bvh->point_basis != HAIROBB_BASIS_BEZIER) bvh->vertices = NULL, bvh->tangents = NULL;   /* never read again */
    *out = bvh;
    return HAIROBB_OK;

failed:
    result = b.error;
    hairobb__builder_free(&b);
    hairobb_free(bvh);
    return result;
}

/* A multi-group BVH's arrays (>>groups): freed and counted with the BVH. */
static void hairobb__free_groups(hairobb_bvh *bvh)
{
    void *user = bvh->allocator_user;
    if (bvh->group_first) HAIROBB_FREE(bvh->group_first, user);
    if (bvh->group_mask) HAIROBB_FREE(bvh->group_mask, user);
    if (bvh->vertex_first) HAIROBB_FREE(bvh->vertex_first, user);
    if (bvh->group_user) HAIROBB_FREE(HAIROBB__CAST(void *, bvh->group_user), user);
    if (bvh->group_vertices) HAIROBB_FREE(bvh->group_vertices, user);
    if (bvh->group_tangents) HAIROBB_FREE(bvh->group_tangents, user);
    if (bvh->group_steps) HAIROBB_FREE(bvh->group_steps, user);
    if (bvh->group_indices) HAIROBB_FREE(bvh->group_indices, user);
    if (bvh->group_step_list) HAIROBB_FREE(HAIROBB__CAST(void *, bvh->group_step_list), user);
    if (bvh->group_shape) HAIROBB_FREE(bvh->group_shape, user);
    if (bvh->round_bits) HAIROBB_FREE(bvh->round_bits, user);
}

/* round_bits' words for n segments */
static size_t hairobb__round_words(size_t n) { return (n + 31) / 32; }

/* The bytes a multi-group BVH holds for its groups (hairobb_memory_bytes). */
static size_t hairobb__group_bytes(const hairobb_bvh *bvh)
{
    size_t points = 4 * sizeof(float) * bvh->vertex_count;
    if (!bvh->group_first) return 0;
    return (size_t)bvh->group_count * (2 * sizeof(uint32_t) + sizeof(size_t) + sizeof(void *) + 1) + sizeof(uint32_t) + sizeof(size_t) +
           (bvh->group_vertices ? points : 0) + (bvh->group_tangents ? points : 0) + bvh->time_steps * (points + sizeof(float *)) +
           sizeof(uint32_t) * bvh->segment_count + (bvh->round_bits ? hairobb__round_words(bvh->segment_count) * sizeof(uint32_t) : 0);
}

HAIROBB_DEF void hairobb_free(hairobb_bvh *bvh)
{
    void *user;
    if (!bvh) return;
    user = bvh->allocator_user;
    if (bvh->points_allocation) HAIROBB_FREE(bvh->points_allocation, user);
    if (bvh->leaf_offsets) HAIROBB_FREE(bvh->leaf_offsets, user);
    if (bvh->owned_indices) HAIROBB_FREE(bvh->owned_indices, user);
    if (bvh->time_vertices) HAIROBB_FREE(HAIROBB__CAST(void *, bvh->time_vertices), user);
    if (bvh->node_allocation) HAIROBB_FREE(bvh->node_allocation, user);
    if (bvh->leaf_prims) HAIROBB_FREE(bvh->leaf_prims, user);
    if (bvh->leaf_ranges) HAIROBB_FREE(bvh->leaf_ranges, user);
    hairobb__free_groups(bvh);
    HAIROBB_FREE(bvh, user);
}

HAIROBB_DEF size_t hairobb_memory_bytes(const hairobb_bvh *bvh)
{
    if (!bvh) return 0;
    return sizeof *bvh + (bvh->node_allocation ? bvh->node_bytes + 64 : 0) + hairobb__leaf_bytes(bvh) +
           (bvh->points_allocation ? hairobb__copy_bytes(bvh->leaf_prim_count, bvh->segment_count) : 0) +
           (bvh->leaf_offsets ? sizeof(uint32_t) * bvh->leaf_prim_count : 0) +
           (bvh->owned_indices ? sizeof(uint32_t) * bvh->segment_count : 0) + bvh->time_steps * sizeof *bvh->time_vertices +
           hairobb__group_bytes(bvh);
}

HAIROBB_DEF void hairobb_get_stats(const hairobb_bvh *bvh, hairobb_stats *stats)
{
    if (!stats) return;
    if (!bvh) { memset(stats, 0, sizeof *stats); return; }
    *stats = bvh->stats;
    /* from the boxes, when asked: the build does not pay for it */
    stats->sah_cost = hairobb__sah_cost(bvh);
    stats->build_sah_cost = bvh->refitted ? bvh->build_sah_cost : stats->sah_cost;
}

HAIROBB_DEF void hairobb_basis_weights(hairobb_basis basis, float u, float w[4], float dw[4])
{
    float s = 1.0f - u, u2 = u * u, u3 = u2 * u, a[4] = {0, 0, 0, 0}, d[4] = {0, 0, 0, 0};
    switch (basis) {
    case HAIROBB_BASIS_BSPLINE:
        a[0] = s * s * s / 6.0f; a[1] = (3.0f * u3 - 6.0f * u2 + 4.0f) / 6.0f;
        a[2] = (-3.0f * u3 + 3.0f * u2 + 3.0f * u + 1.0f) / 6.0f; a[3] = u3 / 6.0f;
        d[0] = -0.5f * s * s; d[1] = 1.5f * u2 - 2.0f * u; d[2] = -1.5f * u2 + u + 0.5f; d[3] = 0.5f * u2;
        break;
    case HAIROBB_BASIS_CATMULL_ROM:
        a[0] = 0.5f * (-u3 + 2.0f * u2 - u); a[1] = 0.5f * (3.0f * u3 - 5.0f * u2 + 2.0f);
        a[2] = 0.5f * (-3.0f * u3 + 4.0f * u2 + u); a[3] = 0.5f * (u3 - u2);
        d[0] = 0.5f * (-3.0f * u2 + 4.0f * u - 1.0f); d[1] = 0.5f * (9.0f * u2 - 10.0f * u);
        d[2] = 0.5f * (-9.0f * u2 + 8.0f * u + 1.0f); d[3] = 0.5f * (3.0f * u2 - 2.0f * u);
        break;
    case HAIROBB_BASIS_HERMITE:
        a[0] = 2.0f * u3 - 3.0f * u2 + 1.0f; a[1] = -2.0f * u3 + 3.0f * u2; a[2] = u3 - 2.0f * u2 + u; a[3] = u3 - u2;
        d[0] = 6.0f * u2 - 6.0f * u; d[1] = -6.0f * u2 + 6.0f * u; d[2] = 3.0f * u2 - 4.0f * u + 1.0f; d[3] = 3.0f * u2 - 2.0f * u;
        break;
    case HAIROBB_BASIS_LINEAR:
        a[0] = s; a[1] = u; d[0] = -1.0f; d[1] = 1.0f;
        break;
    default:   /* Bezier */
        a[0] = s * s * s; a[1] = 3.0f * u * s * s; a[2] = 3.0f * u2 * s; a[3] = u3;
        d[0] = -3.0f * s * s; d[1] = 3.0f * s * s - 6.0f * u * s; d[2] = 6.0f * u * s - 3.0f * u2; d[3] = 3.0f * u2;
        break;
    }
    if (w) memcpy(w, a, sizeof a);
    if (dw) memcpy(dw, d, sizeof d);
}

HAIROBB_DEF int hairobb_interpolate(const hairobb_bvh *bvh, uint32_t group_id, uint32_t prim_id, float u, float time, float p[4],
                                    float d1[4], float d2[4])
{
    float scratch[16], w[4], dw[4], s = 1.0f - u;
    const float *cp;
    size_t prim = prim_id;
    int k;
    if (!bvh) return 0;
    if (bvh->group_first) {
        if (group_id >= bvh->group_count || prim_id >= bvh->group_first[group_id + 1] - bvh->group_first[group_id]) return 0;
        prim += bvh->group_first[group_id];
    } else if (group_id != 0) {
        return 0;
    }
    if (prim >= bvh->segment_count || (bvh->time_steps && !(time >= 0.0f && time <= 1.0f))) return 0;
    cp = hairobb__segment_points(bvh, (uint32_t)prim, time, scratch);   /* the Bezier points traced */
    hairobb_basis_weights(HAIROBB_BASIS_BEZIER, u, w, dw);
    for (k = 0; k < 4; ++k) {
        if (p) p[k] = w[0] * cp[k] + w[1] * cp[4 + k] + w[2] * cp[8 + k] + w[3] * cp[12 + k];
        if (d1) d1[k] = dw[0] * cp[k] + dw[1] * cp[4 + k] + dw[2] * cp[8 + k] + dw[3] * cp[12 + k];
        if (d2) d2[k] = 6.0f * (s * (cp[8 + k] - 2.0f * cp[4 + k] + cp[k]) + u * (cp[12 + k] - 2.0f * cp[8 + k] + cp[4 + k]));
    }
    return 1;
}

HAIROBB_DEF void hairobb_bounds(const hairobb_bvh *bvh, float lower[3], float upper[3])
{
    if (!bvh || !lower || !upper) return;
    memcpy(lower, bvh->lower, sizeof bvh->lower);
    memcpy(upper, bvh->upper, sizeof bvh->upper);
}

/* ------------------------------------------------------------------------ */
/* >>refit  Refit: a built tree over new positions, and its SAH cost        */
/* ------------------------------------------------------------------------ */
/* Surface area of child `lane`'s box as the node stores it (padded,
   quantised), in world units: its extents over the lengths of its frame's
   rows (127 for byte rotations, 1/extent in an affine map's rows). */
static float hairobb__child_area(const unsigned char *node_memory, unsigned type, int lane)
{
    float extent[3];
    int k;
    if (type == HAIROBB__REF_AABB || type == HAIROBB__REF_ROTATED) {
        const float *lower = type == HAIROBB__REF_AABB
            ? HAIROBB__CAST(const hairobb__aabb_node *, (const void *)node_memory)->lower[0]
            : HAIROBB__CAST(const hairobb__rotated_node *, (const void *)node_memory)->lower[0];
        for (k = 0; k < 3; ++k) extent[k] = lower[3 * HAIROBB__W + k * HAIROBB__W + lane] - lower[k * HAIROBB__W + lane];
    } else if (type == HAIROBB__REF_OBB) {
        const hairobb__obb_node *node = HAIROBB__CAST(const hairobb__obb_node *, (const void *)node_memory);
        for (k = 0; k < 3; ++k) {
            float a = node->xfm[3 * k][lane], b = node->xfm[3 * k + 1][lane], c = node->xfm[3 * k + 2][lane];
            extent[k] = 1.0f / sqrtf(a * a + b * b + c * c);
        }
    } else {
        float frames[HAIROBB__W][9], end[3];
        const float *step, *frame;
        const signed char *planes, *ends;
        if (HAIROBB__STILL_TYPE(type) == HAIROBB__REF_QOBB_PER_CHILD) {
            /* this lane's rotation, decoded as hairobb__node_frames decodes it */
            const hairobb__compressed_obb_node *node = HAIROBB__CAST(const hairobb__compressed_obb_node *, (const void *)node_memory);
            for (k = 0; k < 9; ++k) frames[0][k] = (float)node->rotation[k][lane];
            frame = frames[0];
            step = node->step; planes = node->lower[0];
        } else {
            const hairobb__compressed_node *node = HAIROBB__CAST(const hairobb__compressed_node *, (const void *)node_memory);
            hairobb__node_frames(node_memory, type, 1, frames);
            frame = frames[0];
            step = node->step; planes = node->lower[0];
        }
        ends = HAIROBB__MOVING(type) ? HAIROBB__CAST(const signed char *, (const void *)(node_memory + hairobb__node_size(type))) : NULL;
        for (k = 0; k < 3; ++k) {
            float scale = step[k] / sqrtf(hairobb__dot3(frame + 3 * k, frame + 3 * k));
            extent[k] = (float)(planes[(3 + k) * HAIROBB__W + lane] - planes[k * HAIROBB__W + lane]) * scale;
            if (ends) end[k] = (float)(ends[(3 + k) * HAIROBB__W + lane] - ends[k * HAIROBB__W + lane]) * scale;
        }
        /* a moving box's extents are lines in time: the mean of their products over [0, 1] */
        if (ends) {
            float area = 0.0f;
            for (k = 0; k < 3; ++k) {
                int j = (k + 1) % 3;
                area += (extent[k] * extent[j] + end[k] * end[j]) / 3.0f + (extent[k] * end[j] + end[k] * extent[j]) / 6.0f;
            }
            return area;
        }
    }
    return extent[0] * extent[1] + extent[1] * extent[2] + extent[2] * extent[0];
}

/* The child references of an inner node and how many are not empty (the
   empty ones come last). */
static int hairobb__children(const unsigned char *nodes, uint64_t ref, uint64_t child[HAIROBB__W])
{
    unsigned type = HAIROBB__REF_TYPE(ref);
    int count = 0;
    memcpy(child, HAIROBB__NODE_AT(nodes, ref) + hairobb__node_size(type) - HAIROBB__W * sizeof(uint64_t),
           HAIROBB__W * sizeof(uint64_t));
    while (count < HAIROBB__W && HAIROBB__REF_TYPE(child[count]) != HAIROBB__REF_EMPTY) ++count;
    return count;
}

/* The cost of subtree ref inside a box of surface area `area`: a node
   costs its children's box tests (HAIROBB__COST_AABB or _OBB each), a
   leaf its segments (HAIROBB__COST_SEGMENT each), as in the builder. */
static double hairobb__sah_subtree(const hairobb_bvh *bvh, uint64_t ref, double area)
{
    unsigned type = HAIROBB__REF_TYPE(ref), still;
    uint64_t child[HAIROBB__W];
    double cost;
    int count, i;
    if (type == HAIROBB__REF_LEAF) return area * (double)HAIROBB__COST_SEGMENT * (double)((ref >> 4) & 15u);
    if (type == HAIROBB__REF_EMPTY) return 0.0;
    count = hairobb__children(bvh->nodes, ref, child);
    still = HAIROBB__STILL_TYPE(type);
    cost = area * (double)count * (double)(still == HAIROBB__REF_AABB || still == HAIROBB__REF_QAABB ? HAIROBB__COST_AABB : HAIROBB__COST_OBB);
    for (i = 0; i < count; ++i)
        cost += hairobb__sah_subtree(bvh, child[i], (double)hairobb__child_area(HAIROBB__NODE_AT(bvh->nodes, ref), type, i));
    return cost;
}

/* The tree's SAH cost from the boxes it stores, over the area of its bounds. */
static double hairobb__sah_cost(const hairobb_bvh *bvh)
{
    double area = (double)hairobb__half_area(bvh->lower, bvh->upper);
    double cost = hairobb__sah_subtree(bvh, bvh->root, area);
    return area > 0.0 ? cost / area : cost;
}

/* A refit keeps the topology and the frames and writes every node's boxes
   with hairobb__write_boxes from the references below each child (each
   reference bounded once per node above it), so a refit to the positions a
   tree was built on gives back its bytes, and the boxes stay as tight as a
   build's in the same frames. Subtrees of the tree's top run as tasks, as
   in the build; the nodes above them are written after them, on the
   calling thread. A node depends on the references alone: any thread count
   writes the same bytes. */
/* What a subtree gives the node above it: the world box of its references
   (the builder's world boxes: the node's centre), and their box in the
   world axes as an axis-aligned node pads and stores it. */
typedef struct hairobb__refit_box {
    float world[6], axis[6];          /* lower, upper */
} hairobb__refit_box;

typedef struct hairobb__refit_task {
    uint64_t ref;
    size_t first;                     /* its first reference, in leaf_prims */
    hairobb__refit_box box;
    int ran;
} hairobb__refit_task;

typedef struct hairobb__refit {
    hairobb__builder b;               /* what hairobb__write_boxes reads: ids = leaf_prims, ranges = leaf_ranges */
    unsigned char *nodes;
    hairobb__frame_prep world;
    float axis_norms[3];              /* hairobb__node_box's radius scale for the world axes */
    size_t task_limit;
    hairobb__refit_task *tasks;       /* NULL: the tasks are only counted */
    size_t task_count;
} hairobb__refit;

static void hairobb__refit_box_empty(hairobb__refit_box *box)
{
    hairobb__box_empty(box->world, box->world + 3);
    hairobb__box_empty(box->axis, box->axis + 3);
}

static void hairobb__refit_box_grow(hairobb__refit_box *box, const hairobb__refit_box *part)
{
    hairobb__box_grow(box->world, box->world + 3, part->world, part->world + 3);
    hairobb__box_grow(box->axis, box->axis + 3, part->axis, part->axis + 3);
}

/* Writes the boxes of node ref over its children's references ranges[],
   around the centre of their world box. */
static void hairobb__refit_node(const hairobb__refit *f, uint64_t ref, const hairobb__range *ranges, int count,
                                const hairobb__refit_box *children, const hairobb__refit_box *box)
{
    unsigned char *node = HAIROBB__NODE_AT(f->nodes, ref);
    unsigned type = HAIROBB__REF_TYPE(ref);
    float centre[3], frames[HAIROBB__W][9], axis_boxes[HAIROBB__W][6];
    int i;
    for (i = 0; i < count; ++i) memcpy(axis_boxes[i], children[i].axis, sizeof axis_boxes[i]);
    hairobb__box_centre(box->world, box->world + 3, centre);
    hairobb__node_frames(node, type, count, frames);
    hairobb__write_boxes(&f->b, node, type, centre, ranges, count, (const float (*)[9])frames, (const float (*)[6])axis_boxes);
}

/* Refits subtree ref, whose references start at `first` (leaves hold
   consecutive ranges of leaf_prims in tree order); returns where they end,
   and their boxes in *box. */
static size_t hairobb__refit_subtree(const hairobb__refit *f, uint64_t ref, size_t first, hairobb__refit_box *box)
{
    uint64_t child[HAIROBB__W];
    hairobb__range ranges[HAIROBB__W];
    hairobb__refit_box boxes[HAIROBB__W];
    int count, i;
    hairobb__refit_box_empty(box);
    if (HAIROBB__REF_TYPE(ref) == HAIROBB__REF_LEAF) {
        size_t end = first + (size_t)((ref >> 4) & 15u), k;
        HAIROBB_ASSERT((size_t)(ref >> 8) == first);
        for (k = first; k < end; ++k) {
            hairobb__refit_box part;
            /* as hairobb__set_range and hairobb__node_box compute them */
            hairobb__ref_box(&f->b, k, &f->world, NULL, NULL, part.world, part.world + 3);
            hairobb__ref_box(&f->b, k, &f->world, NULL, f->axis_norms, part.axis, part.axis + 3);
            hairobb__refit_box_grow(box, &part);
        }
        return end;
    }
    count = hairobb__children(f->nodes, ref, child);
    for (i = 0; i < count; ++i) {
        ranges[i].begin = first;
        first = ranges[i].end = ranges[i].cap = hairobb__refit_subtree(f, child[i], first, &boxes[i]);
        hairobb__refit_box_grow(box, &boxes[i]);
    }
    hairobb__refit_node(f, ref, ranges, count, boxes, box);
    return first;
}

/* The first reference of subtree ref: its leftmost leaf's. */
static size_t hairobb__first_reference(const unsigned char *nodes, uint64_t ref)
{
    while (HAIROBB__REF_TYPE(ref) != HAIROBB__REF_LEAF) {
        uint64_t child[HAIROBB__W];
        hairobb__children(nodes, ref, child);
        ref = child[0];
    }
    return (size_t)(ref >> 8);
}

/* The tree's top, subtree ref over the references [first, end): subtrees
   of at most task_limit references are tasks, counted or (f->tasks) listed
   before they run; once they ran (finish), their boxes give the nodes
   above them, written here. */
static void hairobb__refit_top(hairobb__refit *f, uint64_t ref, size_t first, size_t end, int finish,
                               hairobb__refit_box *box)
{
    uint64_t child[HAIROBB__W];
    hairobb__range ranges[HAIROBB__W];
    hairobb__refit_box boxes[HAIROBB__W];
    int count, i;
    if (HAIROBB__REF_TYPE(ref) == HAIROBB__REF_LEAF || end - first <= f->task_limit) {
        hairobb__refit_task *task = f->tasks ? &f->tasks[f->task_count] : NULL;
        if (task && finish) {
            *box = task->box;
        } else if (task) {
            task->ref = ref;
            task->first = first;
            task->ran = 0;
        }
        f->task_count++;
        return;
    }
    hairobb__refit_box_empty(box);
    count = hairobb__children(f->nodes, ref, child);
    for (i = 0; i < count; ++i) {
        size_t child_end = i + 1 < count ? hairobb__first_reference(f->nodes, child[i + 1]) : end;
        ranges[i].begin = first;
        ranges[i].end = ranges[i].cap = child_end;
        hairobb__refit_top(f, child[i], first, child_end, finish, &boxes[i]);
        hairobb__refit_box_grow(box, &boxes[i]);
        first = child_end;
    }
    if (finish) hairobb__refit_node(f, ref, ranges, count, boxes, box);
}

/* One task, called by the pool or a user's parallel_for. */
static void hairobb__refit_task_at(void *context, unsigned index)
{
    hairobb__refit *f = HAIROBB__CAST(hairobb__refit *, context);
    hairobb__refit_task *task = &f->tasks[index];
    hairobb__refit_subtree(f, task->ref, task->first, &task->box);
    task->ran = 1;
}

/* Every node's boxes and the bounds for bvh->vertices. It
   cannot fail: without memory for the task list it runs on the calling
   thread alone, and it runs the tasks a user's parallel_for skipped. */
static void hairobb__refit_tree(hairobb_bvh *bvh)
{
    hairobb__refit f;
    hairobb__refit_box box;
    float identity[9], *lower = box.world, *upper = box.world + 3;
    size_t count = bvh->leaf_prim_count, k;
    if (!bvh->refitted) bvh->build_sah_cost = hairobb__sah_cost(bvh);
    bvh->refitted = 1;
    memset(&f, 0, sizeof f);
    f.b.vertices = bvh->vertices;
    f.b.indices = bvh->indices;
    f.b.basis = bvh->point_basis;
    f.b.tangents = bvh->tangents;
    f.b.time_steps = bvh->time_steps;
    f.b.time_vertices = bvh->time_vertices;
    f.b.ids = bvh->leaf_prims;
    f.b.ranges = bvh->leaf_ranges;
    f.b.user = bvh->allocator_user;
    f.nodes = bvh->nodes;
    hairobb__identity_frame(identity);
    hairobb__prepare_frame(identity, &f.world);
    for (k = 0; k < 3; ++k) f.axis_norms[k] = 1.0f + 1.0f / 1048576.0f;   /* hairobb__node_box's for unit rows */
    /* as the build's tasks: about HAIROBB__TASKS of them */
    f.task_limit = hairobb__task_limit(count);
    if (count > f.task_limit) {
        hairobb__refit_top(&f, bvh->root, 0, count, 0, &box);
        f.tasks = HAIROBB__CAST(hairobb__refit_task *, HAIROBB_MALLOC(f.task_count * sizeof *f.tasks, f.b.user));
    }
    if (f.tasks) {
        size_t task_count = f.task_count;
        f.task_count = 0;
        hairobb__refit_top(&f, bvh->root, 0, count, 0, &box);
        hairobb__run_parts(bvh->threads, bvh->parallel_for, bvh->parallel_for_user, task_count, hairobb__refit_task_at, &f);
        for (k = 0; k < task_count; ++k)
            if (!f.tasks[k].ran) hairobb__refit_task_at(&f, (unsigned)k);
        f.task_count = 0;
        hairobb__refit_top(&f, bvh->root, 0, count, 1, &box);
        HAIROBB_FREE(f.tasks, f.b.user);
    } else {
        hairobb__refit_subtree(&f, bvh->root, 0, &box);
    }
    if (bvh->leaf_ranges) {
        /* the bounds are the whole segments', not their clipped parts' */
        hairobb__box_empty(lower, upper);
        for (k = 0; k < bvh->segment_count; ++k) {
            unsigned step;
            for (step = 0; step < (bvh->time_steps ? bvh->time_steps : 1u); ++step) {   /* every step's */
                float lo[3], hi[3], scratch[16];
                const float *cp = bvh->time_steps ? hairobb__builder_points(&f.b, bvh->time_vertices[step], (uint32_t)k, scratch)
                                                  : hairobb__segment_points(bvh, (uint32_t)k, 0.0f, scratch);
                hairobb__segment_box_prep(cp, &f.world, NULL, NULL, lo, hi);
                hairobb__box_grow(lower, upper, lo, hi);
            }
        }
    }
    hairobb__pad_box(lower, upper);
    memcpy(bvh->lower, lower, sizeof bvh->lower);
    memcpy(bvh->upper, upper, sizeof bvh->upper);
}

/* hairobb_refit_tangents for every BVH (a multi-group one's concatenation too) */
static hairobb_result hairobb__refit_arrays(hairobb_bvh *bvh, const float *vertices, const float *tangents)
{
    const uint32_t *indices;
    hairobb_result result;
    if (!bvh || !vertices || (bvh->basis == HAIROBB_BASIS_HERMITE) != (tangents != NULL) || bvh->time_steps)
        return HAIROBB_ERROR_INVALID_ARGUMENT;
    indices = bvh->source_indices;
    /* all checked before anything is written: on an error the BVH traces the old positions */
    result = hairobb__validate(vertices, bvh->vertex_count, indices, bvh->segment_count, hairobb__basis_points(bvh->basis), tangents);
    if (result != HAIROBB_OK) return result;
    bvh->vertices = vertices;
    bvh->tangents = tangents;
    (void)hairobb__copy_points(bvh);   /* its memory is there: cannot fail */
    hairobb__refit_tree(bvh);           /* from the caller's new points, as the build read them */
    if (bvh->copy_points && bvh->point_basis != HAIROBB_BASIS_BEZIER) bvh->vertices = NULL, bvh->tangents = NULL;
    return HAIROBB_OK;
}

/* A multi-group BVH refits one group at a time (hairobb_refit_group): its
   arrays are the BVH's own. */
HAIROBB_DEF hairobb_result hairobb_refit_tangents(hairobb_bvh *bvh, const float *vertices, const float *tangents)
{
    if (bvh && bvh->group_first) return HAIROBB_ERROR_INVALID_ARGUMENT;
    return hairobb__refit_arrays(bvh, vertices, tangents);
}

HAIROBB_DEF hairobb_result hairobb_refit(hairobb_bvh *bvh, const float *vertices)
{
    return hairobb_refit_tangents(bvh, vertices, NULL);
}

static hairobb_result hairobb__refit_steps(hairobb_bvh *bvh, const float *const *time_vertices)
{
    hairobb_build_options opt;
    hairobb_result result;
    const float *vertices = NULL;
    unsigned steps, k;
    if (!bvh || !bvh->time_steps || !time_vertices) return HAIROBB_ERROR_INVALID_ARGUMENT;
    memset(&opt, 0, sizeof opt);
    opt.time_steps = bvh->time_steps;
    opt.time_vertices = time_vertices;
    opt.basis = bvh->basis;
    /* all checked before anything is written: on an error the BVH traces the old positions */
    result = hairobb__validate_motion(&opt, bvh->vertex_count, bvh->indices, bvh->segment_count, &vertices, &steps);
    if (result != HAIROBB_OK) return result;
    for (k = 0; k < steps; ++k) bvh->time_vertices[k] = time_vertices[k];
    bvh->vertices = vertices;
    hairobb__refit_tree(bvh);
    return HAIROBB_OK;
}

HAIROBB_DEF hairobb_result hairobb_refit_motion(hairobb_bvh *bvh, const float *const *time_vertices)
{
    if (bvh && bvh->group_first) return HAIROBB_ERROR_INVALID_ARGUMENT;
    return hairobb__refit_steps(bvh, time_vertices);
}

/* ------------------------------------------------------------------------ */
/* >>groups  Several hair groups in one BVH                                 */
/* ------------------------------------------------------------------------ */
/* A multi-group BVH is hairobb_build's BVH over one concatenation of the
   groups' arrays, which it owns: the tree, the traversal and the
   intersector are the one BVH's, so it traces as fast as one BVH over the
   same hair and hits the same segments. What groups add is a segment's
   group (hairobb__group_of: a binary search of group_first, where a hit's
   ids are written and where a ray mask excludes groups), the groups'
   masks at the leaves, and strands that never join across groups. */

/* The points of one group's time step k (k = -1: static) within the concatenation. */
static float *hairobb__group_points(const hairobb_bvh *bvh, uint32_t group, int step)
{
    float *base = step < 0 ? bvh->group_vertices : bvh->group_steps + 4 * bvh->vertex_count * (size_t)step;
    return base + 4 * bvh->vertex_first[group];
}

/* Checks the groups and counts their vertices and segments (TOO_LARGE
   past 2^32 - 1 of either, as indices are 32 bits). */
static hairobb_result hairobb__check_groups(const hairobb_group *groups, size_t group_count, const hairobb_build_options *opt,
                                            size_t *vertex_total, size_t *segment_total)
{
    size_t g, i, points = hairobb__basis_points(opt->basis);
    unsigned k, steps = opt->time_steps >= 2 ? opt->time_steps : 0u;
    *vertex_total = *segment_total = 0;
    if (!groups || group_count == 0 || group_count > 0xfffffffeu) return HAIROBB_ERROR_INVALID_ARGUMENT;
    for (g = 0; g < group_count; ++g) {
        const hairobb_group *group = &groups[g];
        if (group->segment_count == 0) continue;
        if ((unsigned)group->shape > HAIROBB_GROUP_SHAPE_ROUND) return HAIROBB_ERROR_INVALID_ARGUMENT;
        if (!group->indices || (steps ? !group->time_vertices : !group->vertices) ||
            (opt->basis == HAIROBB_BASIS_HERMITE) != (group->tangents != NULL))
            return HAIROBB_ERROR_INVALID_ARGUMENT;
        for (k = 0; k < steps; ++k)
            if (!group->time_vertices[k]) return HAIROBB_ERROR_INVALID_ARGUMENT;
        if (group->vertex_count > 0xffffffffu - *vertex_total || group->segment_count > 0xffffffffu - *segment_total)
            return HAIROBB_ERROR_TOO_LARGE;
        /* each index within its own group's points (in the concatenation it
           would reach the next group's) */
        for (i = 0; i < group->segment_count; ++i)
            if (group->vertex_count < points || group->indices[i] > group->vertex_count - points) return HAIROBB_ERROR_INDEX_OUT_OF_RANGE;
        *vertex_total += group->vertex_count;
        *segment_total += group->segment_count;
    }
    return *segment_total ? HAIROBB_OK : HAIROBB_ERROR_INVALID_ARGUMENT;
}

/* The groups checked and concatenated into scratch's arrays (a BVH
   struct that holds only them, freed with hairobb__free_groups on an
   error), opt's tangents and steps pointed at the concatenation's. */
static hairobb_result hairobb__take_groups(const hairobb_group *groups, size_t group_count, hairobb_build_options *opt,
                                           hairobb_bvh *scratch)
{
    hairobb_result result;
    size_t vertex_total, segment_total, g, i, points_bytes;
    unsigned k, steps = opt->time_steps >= 2 ? opt->time_steps : 0u;
    void *user = opt->allocator_user;
    /* the rest of the options as hairobb_build and hairobb_load judge them */
    if ((unsigned)opt->basis > HAIROBB_BASIS_LINEAR || opt->time_steps > HAIROBB__MAX_TIME_STEPS) return HAIROBB_ERROR_INVALID_ARGUMENT;
    result = hairobb__check_groups(groups, group_count, opt, &vertex_total, &segment_total);
    if (result != HAIROBB_OK) return result;
    if (vertex_total > (size_t)-1 / (4 * sizeof(float)) / (steps + 2)) return HAIROBB_ERROR_TOO_LARGE;
    points_bytes = 4 * sizeof(float) * vertex_total;
    memset(scratch, 0, sizeof *scratch);
    scratch->allocator_user = user;
    scratch->group_count = (uint32_t)group_count;
    scratch->vertex_count = vertex_total;
    scratch->segment_count = segment_total;
    scratch->time_steps = steps;
    scratch->group_first = HAIROBB__CAST(uint32_t *, HAIROBB_MALLOC((group_count + 1) * sizeof(uint32_t), user));
    scratch->group_mask = HAIROBB__CAST(uint32_t *, HAIROBB_MALLOC(group_count * sizeof(uint32_t), user));
    scratch->vertex_first = HAIROBB__CAST(size_t *, HAIROBB_MALLOC((group_count + 1) * sizeof(size_t), user));
    scratch->group_user = HAIROBB__CAST(void **, HAIROBB_MALLOC(group_count * sizeof(void *), user));
    scratch->group_shape = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(group_count, user));
    scratch->group_indices = HAIROBB__CAST(uint32_t *, hairobb__malloc_large(segment_total * sizeof(uint32_t), user));
    if (!steps) scratch->group_vertices = HAIROBB__CAST(float *, hairobb__malloc_large(points_bytes ? points_bytes : 16, user));
    if (opt->basis == HAIROBB_BASIS_HERMITE)
        scratch->group_tangents = HAIROBB__CAST(float *, hairobb__malloc_large(points_bytes ? points_bytes : 16, user));
    if (steps) {
        scratch->group_steps = HAIROBB__CAST(float *, hairobb__malloc_large(steps * points_bytes, user));
        scratch->group_step_list = HAIROBB__CAST(const float **, HAIROBB_MALLOC(steps * sizeof(float *), user));
    }
    if (!scratch->group_first || !scratch->group_mask || !scratch->vertex_first || !scratch->group_user || !scratch->group_shape ||
        !scratch->group_indices ||
        (!steps && !scratch->group_vertices) || (opt->basis == HAIROBB_BASIS_HERMITE && !scratch->group_tangents) ||
        (steps && (!scratch->group_steps || !scratch->group_step_list))) {
        hairobb__free_groups(scratch);
        return HAIROBB_ERROR_OUT_OF_MEMORY;
    }
    scratch->group_first[0] = 0;
    scratch->vertex_first[0] = 0;
    scratch->group_mask_and = 0xffffffffu;
    for (g = 0; g < group_count; ++g) {
        const hairobb_group *group = &groups[g];
        size_t n = group->segment_count ? group->vertex_count : 0, first = scratch->vertex_first[g];
        uint32_t base = scratch->group_first[g];
        scratch->vertex_first[g + 1] = first + n;
        scratch->group_first[g + 1] = base + (uint32_t)group->segment_count;
        scratch->group_mask[g] = group->mask ? group->mask : 0xffffffffu;
        scratch->group_mask_and &= scratch->group_mask[g];
        scratch->group_user[g] = group->user;
        scratch->group_shape[g] = (unsigned char)group->shape;   /* as asked: hairobb__group_shapes resolves it */
        for (i = 0; i < group->segment_count; ++i) scratch->group_indices[base + i] = group->indices[i] + (uint32_t)first;
        if (!n) continue;
        if (!steps) memcpy(hairobb__group_points(scratch, (uint32_t)g, -1), group->vertices, 4 * sizeof(float) * n);
        if (scratch->group_tangents) memcpy(scratch->group_tangents + 4 * first, group->tangents, 4 * sizeof(float) * n);
        for (k = 0; k < steps; ++k) memcpy(hairobb__group_points(scratch, (uint32_t)g, (int)k), group->time_vertices[k], 4 * sizeof(float) * n);
    }
    for (k = 0; k < steps; ++k) scratch->group_step_list[k] = scratch->group_steps + 4 * vertex_total * (size_t)k;
    opt->tangents = scratch->group_tangents;
    opt->time_vertices = steps ? scratch->group_step_list : NULL;
    return HAIROBB_OK;
}

/* Each group's shape as asked (HAIROBB_GROUP_SHAPE_*, in group_shape since
   hairobb__take_groups) resolved against `shape`, options.shape at a
   build. Returns whether a group with segments is round. */
static int hairobb__group_shapes(hairobb_bvh *scratch, hairobb_shape shape)
{
    uint32_t g;
    int round = 0;
    for (g = 0; g < scratch->group_count; ++g) {
        unsigned asked = scratch->group_shape[g];
        scratch->group_shape[g] = (unsigned char)(asked == HAIROBB_GROUP_SHAPE_ROUND   ? HAIROBB_SHAPE_ROUND
                                                  : asked == HAIROBB_GROUP_SHAPE_RIBBON ? HAIROBB_SHAPE_RIBBON
                                                                                        : shape);
        if (scratch->group_shape[g] == HAIROBB_SHAPE_ROUND && scratch->group_first[g + 1] > scratch->group_first[g]) round = 1;
    }
    return round;
}

/* round_bits, where the groups with segments are of both shapes (MIXED
   SHAPES): OUT_OF_MEMORY or OK. */
static hairobb_result hairobb__group_round_bits(hairobb_bvh *scratch)
{
    uint32_t g, s, seen = 0;
    size_t words = hairobb__round_words(scratch->segment_count);
    for (g = 0; g < scratch->group_count; ++g)
        if (scratch->group_first[g + 1] > scratch->group_first[g]) seen |= 1u << scratch->group_shape[g];
    if (seen != 3u) return HAIROBB_OK;
    scratch->round_bits = HAIROBB__CAST(uint32_t *, hairobb__malloc_large(words * sizeof(uint32_t), scratch->allocator_user));
    if (!scratch->round_bits) return HAIROBB_ERROR_OUT_OF_MEMORY;
    memset(scratch->round_bits, 0, words * sizeof(uint32_t));
    for (g = 0; g < scratch->group_count; ++g)
        if (scratch->group_shape[g] == HAIROBB_SHAPE_ROUND)
            for (s = scratch->group_first[g]; s < scratch->group_first[g + 1]; ++s) scratch->round_bits[s >> 5] |= 1u << (s & 31u);
    return HAIROBB_OK;
}

/* scratch's arrays moved into the BVH built or loaded over them. */
static void hairobb__attach_groups(hairobb_bvh *bvh, const hairobb_bvh *scratch)
{
    bvh->group_count = scratch->group_count;
    bvh->group_first = scratch->group_first;
    bvh->group_mask = scratch->group_mask;
    bvh->vertex_first = scratch->vertex_first;
    bvh->group_user = scratch->group_user;
    bvh->group_mask_and = scratch->group_mask_and;
    bvh->group_vertices = scratch->group_vertices;
    bvh->group_tangents = scratch->group_tangents;
    bvh->group_steps = scratch->group_steps;
    bvh->group_indices = scratch->group_indices;
    bvh->group_step_list = scratch->group_step_list;
    bvh->group_shape = scratch->group_shape;
    bvh->round_bits = scratch->round_bits;
    if (bvh->copy_points && bvh->point_basis == HAIROBB_BASIS_BEZIER) {
        /* the copy holds every segment's points: a refit gathers the
           groups' points from it (hairobb_refit_group), so the
           concatenation's points go, and the BVH is one BVH's size but
           for its indices */
        HAIROBB_FREE(bvh->group_vertices, bvh->allocator_user);
        bvh->group_vertices = NULL;
        bvh->vertices = NULL;
    }
}

HAIROBB_DEF hairobb_result hairobb_build_groups(const hairobb_group *groups, size_t group_count,
                                                const hairobb_build_options *options, hairobb_bvh **out)
{
    hairobb_build_options opt = options ? *options : hairobb_default_options();
    hairobb_bvh scratch;   /* the groups' arrays, moved into the BVH once it is built */
    hairobb_result result;
    if (out) *out = NULL;
    if (!out) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if ((unsigned)opt.shape > HAIROBB_SHAPE_ROUND) return HAIROBB_ERROR_INVALID_ARGUMENT;
    result = hairobb__take_groups(groups, group_count, &opt, &scratch);
    if (result != HAIROBB_OK) return result;
    /* a BVH with a round group builds as round (its caps and culling);
       segments read their own shape where groups mix them */
    opt.shape = hairobb__group_shapes(&scratch, opt.shape) ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
    result = hairobb__group_round_bits(&scratch);
    if (result == HAIROBB_OK)
        result = hairobb_build(scratch.group_vertices, scratch.vertex_count, scratch.group_indices, scratch.segment_count, &opt, out);
    if (result != HAIROBB_OK) {
        hairobb__free_groups(&scratch);
        return result;
    }
    hairobb__attach_groups(*out, &scratch);
    return HAIROBB_OK;
}

/* Refit of a static Bezier BVH whose points are only in its copy: every
   segment's points gathered from the copy into a concatenation (a segment
   of another group reads its own 4 points; points no segment reads stay
   0), the group's new points over its part, and a refit from that. */
static hairobb_result hairobb__refit_from_copy(hairobb_bvh *bvh, uint32_t group_id, const float *vertices)
{
    size_t bytes = 4 * sizeof(float) * bvh->vertex_count, s;
    float *gathered = HAIROBB__CAST(float *, hairobb__malloc_large(bytes ? bytes : 16, bvh->allocator_user)), scratch[16];
    hairobb_result result;
    if (!gathered) return HAIROBB_ERROR_OUT_OF_MEMORY;
    memset(gathered, 0, bytes);
    for (s = 0; s < bvh->segment_count; ++s)
        memcpy(gathered + 4 * (size_t)bvh->group_indices[s], hairobb__segment_points(bvh, (uint32_t)s, 0.0f, scratch), 16 * sizeof(float));
    memcpy(gathered + 4 * bvh->vertex_first[group_id], vertices, 4 * sizeof(float) * (bvh->vertex_first[group_id + 1] - bvh->vertex_first[group_id]));
    result = hairobb__refit_arrays(bvh, gathered, NULL);
    bvh->vertices = NULL;   /* the copy is traced, never these */
    HAIROBB_FREE(gathered, bvh->allocator_user);
    return result;
}

HAIROBB_DEF hairobb_result hairobb_refit_group(hairobb_bvh *bvh, uint32_t group_id, const float *vertices, const float *tangents,
                                               const float *const *time_vertices)
{
    size_t n, bytes, first;
    float *saved;
    hairobb_result result;
    unsigned k, steps;
    int step;
    if (!bvh || !bvh->group_first || group_id >= bvh->group_count) return HAIROBB_ERROR_INVALID_ARGUMENT;
    steps = bvh->time_steps;
    if ((steps ? !time_vertices || vertices : !vertices || time_vertices != NULL) ||
        (bvh->basis == HAIROBB_BASIS_HERMITE) != (tangents != NULL))
        return HAIROBB_ERROR_INVALID_ARGUMENT;
    for (k = 0; k < steps; ++k)
        if (!time_vertices[k]) return HAIROBB_ERROR_INVALID_ARGUMENT;
    first = bvh->vertex_first[group_id];
    n = bvh->vertex_first[group_id + 1] - first;
    bytes = 4 * sizeof(float) * n;
    if (n == 0) return HAIROBB_OK;   /* a group without segments */
    if (!steps && !bvh->group_vertices) return hairobb__refit_from_copy(bvh, group_id, vertices);
    /* copied in, the old points kept until the new ones validate */
    saved = HAIROBB__CAST(float *, HAIROBB_MALLOC(bytes * ((steps ? steps : 1u) + (tangents ? 1u : 0u)), bvh->allocator_user));
    if (!saved) return HAIROBB_ERROR_OUT_OF_MEMORY;
    for (step = steps ? 0 : -1; step < (int)steps; ++step) {
        memcpy(saved + 4 * n * (size_t)(step + (steps ? 0 : 1)), hairobb__group_points(bvh, group_id, step), bytes);
        memcpy(hairobb__group_points(bvh, group_id, step), steps ? time_vertices[step] : vertices, bytes);
    }
    if (tangents) {
        memcpy(saved + 4 * n, bvh->group_tangents + 4 * first, bytes);
        memcpy(bvh->group_tangents + 4 * first, tangents, bytes);
    }
    result = steps ? hairobb__refit_steps(bvh, bvh->group_step_list) : hairobb__refit_arrays(bvh, bvh->group_vertices, bvh->group_tangents);
    if (result != HAIROBB_OK) {   /* as it was */
        for (step = steps ? 0 : -1; step < (int)steps; ++step)
            memcpy(hairobb__group_points(bvh, group_id, step), saved + 4 * n * (size_t)(step + (steps ? 0 : 1)), bytes);
        if (tangents) memcpy(bvh->group_tangents + 4 * first, saved + 4 * n, bytes);
    }
    HAIROBB_FREE(saved, bvh->allocator_user);
    return result;
}

HAIROBB_DEF uint32_t hairobb_group_count(const hairobb_bvh *bvh)
{
    return !bvh ? 0u : bvh->group_first ? bvh->group_count : 1u;
}

HAIROBB_DEF void *hairobb_group_user(const hairobb_bvh *bvh, uint32_t group_id)
{
    return bvh && bvh->group_first && group_id < bvh->group_count ? bvh->group_user[group_id] : NULL;
}

HAIROBB_DEF size_t hairobb_group_segments(const hairobb_bvh *bvh, uint32_t group_id)
{
    if (!bvh) return 0;
    if (!bvh->group_first) return group_id == 0 ? bvh->segment_count : 0;
    return group_id < bvh->group_count ? (size_t)(bvh->group_first[group_id + 1] - bvh->group_first[group_id]) : 0;
}

HAIROBB_DEF uint32_t hairobb_get_group_stats(const hairobb_bvh *bvh, hairobb_group_stats *stats, uint32_t count)
{
    uint32_t groups = hairobb_group_count(bvh), g;
    size_t i, own_total = 0, shared, references = 0, total = hairobb_memory_bytes(bvh), share_before = 0;
    size_t points = bvh && bvh->group_first ? (bvh->group_vertices ? 1u : 0u) + (bvh->group_tangents ? 1u : 0u) + bvh->time_steps : 0;
    if (!bvh || !stats) return 0;
    if (count > groups) count = groups;
    if (!bvh->group_first) {   /* one group: everything */
        if (count == 0) return 0;
        stats[0].segment_count = bvh->segment_count;
        stats[0].vertex_count = bvh->vertex_count;
        stats[0].leaf_references = bvh->leaf_prim_count;
        stats[0].bytes = total;
        stats[0].shape = bvh->shape;
        return 1;
    }
    for (g = 0; g < count; ++g) stats[g].leaf_references = 0;
    for (i = 0; i < bvh->leaf_prim_count; ++i) {
        uint32_t group = hairobb__group_of(bvh, bvh->leaf_prims[i]);
        if (group < count) ++stats[group].leaf_references;
    }
    /* what is held for each group alone: its points (static, tangents,
       every step: 16 bytes a point each) and its indices (4 a segment) */
    for (g = 0; g < groups; ++g) {
        size_t segments = bvh->group_first[g + 1] - bvh->group_first[g], vertices = bvh->vertex_first[g + 1] - bvh->vertex_first[g];
        own_total += points * 4 * sizeof(float) * vertices + sizeof(uint32_t) * segments;
    }
    shared = total - own_total;
    for (g = 0; g < count; ++g) {
        size_t segments = bvh->group_first[g + 1] - bvh->group_first[g], vertices = bvh->vertex_first[g + 1] - bvh->vertex_first[g];
        size_t share_after;
        references += stats[g].leaf_references;
        /* the shared bytes by cumulative references: the shares add up */
        share_after = (size_t)((double)shared * (double)references / (double)bvh->leaf_prim_count);
        if (g + 1 == groups) share_after = shared;
        stats[g].segment_count = segments;
        stats[g].vertex_count = vertices;
        stats[g].bytes = points * 4 * sizeof(float) * vertices + sizeof(uint32_t) * segments + (share_after - share_before);
        stats[g].shape = (hairobb_shape)bvh->group_shape[g];
        share_before = share_after;
    }
    return count;
}

/* ------------------------------------------------------------------------ */
/* >>save_load  Save and load                                               */
/* ------------------------------------------------------------------------ */
/* The format (host byte order; the byte-order word tells another host's):
     header, HAIROBB__SAVE_HEADER bytes at the offsets HAIROBB__AT_*;
     the node memory, node_bytes bytes, as the traversal reads it;
     leaf_prims, 4 bytes each, then zeros to a multiple of 8;
     where flags has HAIROBB__SAVE_RANGES (a spatial-split tree that clipped
     segments), leaf_ranges: u0, u1 of each leaf_prims entry, 8 bytes each;
     where flags has HAIROBB__SAVE_GROUPS (a multi-group BVH, format 3 on):
     the group count G (8 bytes), each group's first segment (G + 1 of 4
     bytes, then zeros to a multiple of 8) and first vertex (G + 1 of 8);
     where flags has HAIROBB__SAVE_SHAPES too (groups of both shapes): each
     group's hairobb_shape, G bytes, then zeros to a multiple of 8 (without
     it every group is the header's shape);
     a checksum of every byte before it (hairobb__hash), 8 bytes.
   The hair hash (hairobb__traced_hash) covers the Bezier segments the BVH
   traces, read from the BVH's own copy where it has one, so that a
   renderer may free Bezier arrays after the build: for other bases the
   converted curves, which are not stored (a load converts the caller's
   arrays again, with the build's code, so the hash also covers tangents).
   Version 1 (0.1.x) hashed Bezier input as the caller's arrays, vertex
   and index, as they were: it still loads. */
#define HAIROBB__SAVE_VERSION ((uint32_t)HAIROBB_SAVE_FORMAT_VERSION)
#define HAIROBB__SAVE_VERSION_OLDEST ((uint32_t)HAIROBB_SAVE_FORMAT_OLDEST)
#define HAIROBB__SAVE_BYTE_ORDER 0x01020304u
#define HAIROBB__SAVE_HEADER 128
#define HAIROBB__SAVE_RANGES 1u         /* leaf_ranges follow leaf_prims */
#define HAIROBB__SAVE_GROUPS 2u         /* the groups' section follows (format 3 on) */
#define HAIROBB__SAVE_SHAPES 4u         /* with HAIROBB__SAVE_GROUPS: the groups' shapes follow it */
#define HAIROBB__AT_VERSION 8           /* uint32 each ... */
#define HAIROBB__AT_BYTE_ORDER 12
#define HAIROBB__AT_WIDTH 16
#define HAIROBB__AT_BASIS 20
#define HAIROBB__AT_PRECISION 24
#define HAIROBB__AT_PIECES 28
#define HAIROBB__AT_LAYOUT 32
#define HAIROBB__AT_MAX_LEAF 36
#define HAIROBB__AT_POLICY 40
#define HAIROBB__AT_FLAGS 44            /* HAIROBB__SAVE_RANGES, HAIROBB__SAVE_GROUPS or 0 */
#define HAIROBB__AT_SEGMENTS 48         /* ... uint64 each ... */
#define HAIROBB__AT_VERTICES 56
#define HAIROBB__AT_HAIR_HASH 64
#define HAIROBB__AT_ROOT 72
#define HAIROBB__AT_NODE_BYTES 80
#define HAIROBB__AT_LEAF_PRIMS 88
#define HAIROBB__AT_BOUNDS 96           /* ... float lower[3], upper[3] */
#define HAIROBB__AT_TIME_STEPS 120      /* uint32: motion blur's steps, 0 static */
#define HAIROBB__AT_SHAPE 124           /* uint32: hairobb_shape in the low byte, HAIROBB__SAVE_CAPS and _CULL above (files before it have 0 here: ribbons) */
#define HAIROBB__SAVE_CAPS 0x100u       /* round curves: end_caps ON */
#define HAIROBB__SAVE_CULL 0x200u       /* round curves: back_faces OFF */
static const unsigned char hairobb__save_magic[8] = {'H', 'A', 'I', 'R', 'O', 'B', 'B', 0x1a};

/* A 64-bit hash of 8-byte words: each step (xor the word, multiply by an
   odd constant, xor-shift) is a bijection of the state, and of the word
   for a given state, so changing any one word always changes the result
   (every single-byte flip is caught). Four lanes take 32-byte blocks (one
   chain's multiply latency would hold it below memory speed), then are
   folded into one, which takes the rest, one zero-padded word, and the
   length. */
HAIROBB__INLINE uint64_t hairobb__hash_word(uint64_t h, uint64_t word)
{
    h = (h ^ word) * UINT64_C(0x9e3779b97f4a7c15);
    return h ^ (h >> 31);
}

static uint64_t hairobb__hash(uint64_t h, const void *data, size_t bytes)
{
    const unsigned char *p = HAIROBB__CAST(const unsigned char *, data);
    uint64_t lane[4], word[4];
    size_t i = 0;
    int k;
    for (k = 0; k < 4; ++k) lane[k] = h + (uint64_t)k;
    for (; i + 32 <= bytes; i += 32) {
        memcpy(word, p + i, 32);
        for (k = 0; k < 4; ++k) lane[k] = hairobb__hash_word(lane[k], word[k]);
    }
    h = hairobb__hash_word(hairobb__hash_word(hairobb__hash_word(lane[0], lane[1]), lane[2]), lane[3]);
    for (; i + 8 <= bytes; i += 8) {
        memcpy(word, p + i, 8);
        h = hairobb__hash_word(h, word[0]);
    }
    if (i < bytes) {
        word[0] = 0;
        memcpy(word, p + i, bytes - i);
        h = hairobb__hash_word(h, word[0]);
    }
    return hairobb__hash_word(h, (uint64_t)bytes);
}

/* The checksum a saved BVH of size bytes ends with. */
static uint64_t hairobb__save_checksum(const unsigned char *saved, size_t size)
{
    return hairobb__hash(UINT64_C(0x68616972), saved, size - 8);
}

/* Control points of the Bezier segments a BVH traces: the caller's, or
   the converted curves' 4 a segment (the hash covers what is traced). */
static size_t hairobb__traced_vertex_count(const hairobb_bvh *bvh)
{
    return bvh->basis != HAIROBB_BASIS_BEZIER && !bvh->time_steps ? 4 * bvh->segment_count : bvh->vertex_count;
}

static uint64_t hairobb__hair_hash(const float *vertices, size_t vertex_count, const uint32_t *indices, size_t segment_count)
{
    uint64_t h = hairobb__hash_word(hairobb__hash_word(UINT64_C(0x6f6262), (uint64_t)vertex_count), (uint64_t)segment_count);
    h = hairobb__hash(h, vertices, 4 * sizeof(float) * vertex_count);
    return hairobb__hash(h, indices, sizeof(uint32_t) * segment_count);
}

/* hairobb__hair_hash of the Bezier segments a BVH traces, or for motion
   blur of the caller's arrays (any basis), every step's. Each segment's
   points are read where the BVH reads them (hairobb__segment_points: the
   copy's, or converted as they are hashed): the same bytes
   hairobb__hash reads from a copy in segment order (two of its 32-byte
   blocks a segment, then the indices 4 i), so a BVH saved with the copy
   loads without it and back. Format version 1 hashed static Bezier input
   as the caller's arrays. */
static uint64_t hairobb__traced_hash(const hairobb_bvh *bvh, uint32_t version)
{
    size_t n = bvh->segment_count, i;
    uint64_t lane[4], word[4], h;
    uint32_t ix[8];
    int k, j;
    if ((version < 2u && bvh->point_basis == HAIROBB_BASIS_BEZIER) || bvh->time_steps) {   /* the arrays as they are */
        size_t vertex_count = hairobb__traced_vertex_count(bvh);
        h = hairobb__hair_hash(bvh->vertices, vertex_count, bvh->indices, n);
        for (k = 1; k < (int)bvh->time_steps; ++k) h = hairobb__hash(h, bvh->time_vertices[k], 4 * sizeof(float) * vertex_count);
        return h;
    }
    h = hairobb__hash_word(hairobb__hash_word(UINT64_C(0x6f6262), (uint64_t)(4 * n)), (uint64_t)n);
    for (k = 0; k < 4; ++k) lane[k] = h + (uint64_t)k;
    for (i = 0; i < n; ++i) {
        float scratch[16];
        const float *cp = hairobb__segment_points(bvh, (uint32_t)i, 0.0f, scratch);
        for (j = 0; j < 2; ++j) {
            memcpy(word, cp + 8 * j, 32);
            for (k = 0; k < 4; ++k) lane[k] = hairobb__hash_word(lane[k], word[k]);
        }
    }
    h = hairobb__hash_word(hairobb__hash_word(hairobb__hash_word(lane[0], lane[1]), lane[2]), lane[3]);
    h = hairobb__hash_word(h, (uint64_t)(64 * n));
    for (k = 0; k < 4; ++k) lane[k] = h + (uint64_t)k;
    for (i = 0; i + 8 <= n; i += 8) {
        for (j = 0; j < 8; ++j) ix[j] = (uint32_t)(4 * (i + (size_t)j));
        memcpy(word, ix, 32);
        for (k = 0; k < 4; ++k) lane[k] = hairobb__hash_word(lane[k], word[k]);
    }
    h = hairobb__hash_word(hairobb__hash_word(hairobb__hash_word(lane[0], lane[1]), lane[2]), lane[3]);
    for (; i + 2 <= n; i += 2) {
        ix[0] = (uint32_t)(4 * i); ix[1] = (uint32_t)(4 * i + 4);
        memcpy(word, ix, 8);
        h = hairobb__hash_word(h, word[0]);
    }
    if (i < n) {
        word[0] = 0;
        ix[0] = (uint32_t)(4 * i);
        memcpy(word, ix, 4);
        h = hairobb__hash_word(h, word[0]);
    }
    return hairobb__hash_word(h, (uint64_t)(4 * n));
}

static void hairobb__put32(unsigned char *at, uint32_t v) { memcpy(at, &v, sizeof v); }
static void hairobb__put64(unsigned char *at, uint64_t v) { memcpy(at, &v, sizeof v); }
static uint32_t hairobb__get32(const unsigned char *at) { uint32_t v; memcpy(&v, at, sizeof v); return v; }
static uint64_t hairobb__get64(const unsigned char *at) { uint64_t v; memcpy(&v, at, sizeof v); return v; }

/* leaf_prims' bytes in the format: a multiple of 8 */
static size_t hairobb__saved_leaf_bytes(size_t leaf_prim_count) { return (sizeof(uint32_t) * leaf_prim_count + 7) & ~(size_t)7; }

/* the groups' section's bytes, for G groups, and the shapes' after it */
static size_t hairobb__saved_group_bytes(uint64_t groups)
{
    return (size_t)(8 + (((groups + 1) * sizeof(uint32_t) + 7) & ~(uint64_t)7) + 8 * (groups + 1));
}
static size_t hairobb__saved_shape_bytes(uint64_t groups) { return (size_t)((groups + 7) & ~(uint64_t)7); }

HAIROBB_DEF size_t hairobb_save_size(const hairobb_bvh *bvh)
{
    if (!bvh) return 0;
    return HAIROBB__SAVE_HEADER + bvh->node_bytes + hairobb__saved_leaf_bytes(bvh->leaf_prim_count) +
           (bvh->leaf_ranges ? 2 * sizeof(float) * bvh->leaf_prim_count : 0) +
           (bvh->group_first ? hairobb__saved_group_bytes(bvh->group_count) : 0) +
           (bvh->round_bits ? hairobb__saved_shape_bytes(bvh->group_count) : 0) + 8;
}

HAIROBB_DEF hairobb_result hairobb_save(const hairobb_bvh *bvh, void *buffer, size_t size)
{
    unsigned char *out = HAIROBB__CAST(unsigned char *, buffer);
    size_t total = hairobb_save_size(bvh), leaf_bytes;
    int k;
    if (!bvh || !out || size < total) return HAIROBB_ERROR_INVALID_ARGUMENT;
    memset(out, 0, HAIROBB__SAVE_HEADER);
    memcpy(out, hairobb__save_magic, sizeof hairobb__save_magic);
    hairobb__put32(out + HAIROBB__AT_VERSION, HAIROBB__SAVE_VERSION);
    hairobb__put32(out + HAIROBB__AT_BYTE_ORDER, HAIROBB__SAVE_BYTE_ORDER);
    hairobb__put32(out + HAIROBB__AT_WIDTH, HAIROBB__W);
    hairobb__put32(out + HAIROBB__AT_BASIS, (uint32_t)bvh->basis);
    hairobb__put32(out + HAIROBB__AT_PRECISION, (uint32_t)bvh->precision);
    hairobb__put32(out + HAIROBB__AT_PIECES, (uint32_t)bvh->pieces);
    hairobb__put32(out + HAIROBB__AT_LAYOUT, (uint32_t)bvh->obb_layout);
    hairobb__put32(out + HAIROBB__AT_MAX_LEAF, bvh->max_leaf_size);
    hairobb__put32(out + HAIROBB__AT_POLICY, (uint32_t)bvh->policy);
    hairobb__put32(out + HAIROBB__AT_FLAGS,
                   (bvh->leaf_ranges ? HAIROBB__SAVE_RANGES : 0u) | (bvh->group_first ? HAIROBB__SAVE_GROUPS : 0u) |
                       (bvh->round_bits ? HAIROBB__SAVE_SHAPES : 0u));
    hairobb__put64(out + HAIROBB__AT_SEGMENTS, bvh->segment_count);
    hairobb__put64(out + HAIROBB__AT_VERTICES, hairobb__traced_vertex_count(bvh));
    hairobb__put64(out + HAIROBB__AT_HAIR_HASH, hairobb__traced_hash(bvh, HAIROBB__SAVE_VERSION));
    hairobb__put32(out + HAIROBB__AT_TIME_STEPS, bvh->time_steps);
    hairobb__put32(out + HAIROBB__AT_SHAPE, (uint32_t)bvh->shape | (bvh->end_caps ? HAIROBB__SAVE_CAPS : 0u) |
                                            (bvh->cull_back_faces ? HAIROBB__SAVE_CULL : 0u));
    hairobb__put64(out + HAIROBB__AT_ROOT, bvh->root);
    hairobb__put64(out + HAIROBB__AT_NODE_BYTES, bvh->node_bytes);
    hairobb__put64(out + HAIROBB__AT_LEAF_PRIMS, bvh->leaf_prim_count);
    for (k = 0; k < 3; ++k) {
        memcpy(out + HAIROBB__AT_BOUNDS + 4 * k, &bvh->lower[k], sizeof(float));
        memcpy(out + HAIROBB__AT_BOUNDS + 12 + 4 * k, &bvh->upper[k], sizeof(float));
    }
    out += HAIROBB__SAVE_HEADER;
    if (bvh->node_bytes) memcpy(out, bvh->nodes, bvh->node_bytes);
    out += bvh->node_bytes;
    leaf_bytes = hairobb__saved_leaf_bytes(bvh->leaf_prim_count);
    memset(out + leaf_bytes - 8, 0, 8);   /* the padding; leaf_bytes >= 8: a tree has a leaf */
    memcpy(out, bvh->leaf_prims, sizeof(uint32_t) * bvh->leaf_prim_count);
    out += leaf_bytes;
    if (bvh->leaf_ranges) {
        memcpy(out, bvh->leaf_ranges, 2 * sizeof(float) * bvh->leaf_prim_count);
        out += 2 * sizeof(float) * bvh->leaf_prim_count;
    }
    if (bvh->group_first) {
        size_t first_bytes = (((size_t)bvh->group_count + 1) * sizeof(uint32_t) + 7) & ~(size_t)7;
        uint32_t g;
        hairobb__put64(out, bvh->group_count);
        memset(out + 8, 0, first_bytes);
        for (g = 0; g <= bvh->group_count; ++g) {
            hairobb__put32(out + 8 + 4 * (size_t)g, bvh->group_first[g]);
            hairobb__put64(out + 8 + first_bytes + 8 * (size_t)g, bvh->vertex_first[g]);
        }
        out += hairobb__saved_group_bytes(bvh->group_count);
        if (bvh->round_bits) {
            memset(out, 0, hairobb__saved_shape_bytes(bvh->group_count));
            memcpy(out, bvh->group_shape, bvh->group_count);
            out += hairobb__saved_shape_bytes(bvh->group_count);
        }
    }
    hairobb__put64(out, hairobb__save_checksum(HAIROBB__CAST(unsigned char *, buffer), total));
    return HAIROBB_OK;
}

/* The walk that proves a loaded tree traceable: every reference is of a
   type the layout and policy make, inside the node memory; every node is
   reached once (a bit per 16 bytes: no cycles, no sharing, no overlap) at
   a depth whose pushes the traversal stack holds; leaves take leaf_prims
   in tree order, exactly once, as hairobb__finish_tree wrote them. It
   counts the statistics as the builder did. */
typedef struct hairobb__tree_check {
    const unsigned char *nodes;
    size_t node_bytes, reached_bytes;
    unsigned char *reached;          /* a bit per 16 bytes of node memory */
    size_t leaf_prim_count, next_leaf;
    unsigned inner_types;            /* bit per node type the file's layout and policy build */
    unsigned max_leaf;
    hairobb_stats stats;
} hairobb__tree_check;

static int hairobb__check_tree(hairobb__tree_check *c, uint64_t ref, unsigned depth)
{
    unsigned type = HAIROBB__REF_TYPE(ref);
    size_t offset = HAIROBB__NODE_OFFSET(ref), stride, granule;
    uint64_t child[HAIROBB__W];
    int i, child_count;
    if (type == HAIROBB__REF_LEAF) {
        uint64_t first = ref >> 8, count = (ref >> 4) & 15u;
        if (count == 0 || count > c->max_leaf || first != c->next_leaf || count > c->leaf_prim_count - c->next_leaf) return 0;
        c->next_leaf += (size_t)count;
        c->stats.leaves++;
        c->stats.leaf_references += (size_t)count;
        if (depth > c->stats.max_depth) c->stats.max_depth = depth;
        return 1;
    }
    /* the traversal reaches an inner node at depth d with at most W - 1
       entries per ancestor on its stack, and pushes its W children before
       taking the nearest: (W - 1) d + W entries */
    if (!(c->inner_types >> type & 1u) || (ref >> 4) > (uint64_t)((size_t)-1 >> 4) ||
        (size_t)(HAIROBB__W - 1) * depth + HAIROBB__W > HAIROBB__STACK)
        return 0;
    stride = hairobb__node_stride(type);   /* with what follows the node (an affine OBB node's directions) */
    if (offset > c->node_bytes || stride > c->node_bytes - offset) return 0;
    for (granule = offset / 16; granule < (offset + stride) / 16; ++granule) {
        if (c->reached[granule / 8] >> (granule % 8) & 1u) return 0;
        c->reached[granule / 8] |= (unsigned char)(1u << (granule % 8));
    }
    c->reached_bytes += stride;
    if (type == HAIROBB__REF_AABB || HAIROBB__STILL_TYPE(type) == HAIROBB__REF_QAABB) c->stats.aabb_nodes++; else c->stats.obb_nodes++;
    /* 2..W children, the empty lanes last (as hairobb__build_node fills them) */
    child_count = hairobb__children(c->nodes, ref, child);
    for (i = child_count; i < HAIROBB__W; ++i)
        if (child[i] != HAIROBB__REF_EMPTY) return 0;
    for (i = 0; i < child_count; ++i)
        if (!hairobb__check_tree(c, child[i], depth + 1)) return 0;
    return child_count >= 2;
}

/* The node types a layout and policy build (hairobb__build_node), for
   still or moving hair. */
static unsigned hairobb__layout_types(hairobb_obb_layout layout, hairobb_node_policy policy, int moving)
{
    unsigned types = 0, aabb = 1u << HAIROBB__REF_AABB | 1u << HAIROBB__REF_QAABB | 1u << HAIROBB__REF_QAABB_MB;
    if (layout == HAIROBB_OBB_PER_CHILD) types = 1u << HAIROBB__REF_AABB | 1u << HAIROBB__REF_OBB;
    if (layout == HAIROBB_OBB_SHARED_ROTATION) types = 1u << HAIROBB__REF_AABB | 1u << HAIROBB__REF_ROTATED;
    if (layout == HAIROBB_OBB_COMPRESSED) types = 1u << HAIROBB__REF_QAABB | 1u << HAIROBB__REF_QOBB;
    if (layout == HAIROBB_OBB_COMPRESSED_PER_CHILD)
        types = 1u << HAIROBB__REF_AABB | 1u << HAIROBB__REF_OBB | 1u << HAIROBB__REF_QOBB_PER_CHILD;
    if (moving && layout == HAIROBB_OBB_COMPRESSED) types = 1u << HAIROBB__REF_QAABB_MB | 1u << HAIROBB__REF_QOBB_MB;
    if (moving && layout == HAIROBB_OBB_COMPRESSED_PER_CHILD) types = 1u << HAIROBB__REF_QAABB_MB | 1u << HAIROBB__REF_QOBB_PER_CHILD_MB;
    if (policy == HAIROBB_NODES_AABB_ONLY) types &= aabb;
    if (policy == HAIROBB_NODES_OBB_ONLY) types &= ~aabb;
    return types;
}

/* What a saved BVH's header says. */
typedef struct hairobb__saved {
    uint64_t node_bytes, leaf_prim_count, segments;
    size_t leaf_bytes, range_bytes;
    uint64_t groups;                  /* a multi-group BVH's group count, its section at group_at; 0: none */
    size_t group_at, shapes_at;       /* shapes_at: the groups' shapes (HAIROBB__SAVE_SHAPES), else 0 */
    uint32_t version, basis, steps;
    hairobb__tree_settings tree;      /* set once the header's words are in range */
} hairobb__saved;

/* The header of the size bytes at in: UNSUPPORTED where this build cannot
   read it; INVALID_FILE unless its sizes add up to size, the checksum
   matches, the settings are in range, the padding is zero and the bounds
   are finite. */
static hairobb_result hairobb__read_saved(const unsigned char *in, size_t size, hairobb__saved *saved)
{
    uint32_t flags, precision, pieces, layout, max_leaf, policy, shape, shape_word;
    size_t i;
    int k;
    if (size < HAIROBB__SAVE_HEADER + 8 || memcmp(in, hairobb__save_magic, sizeof hairobb__save_magic) != 0)
        return HAIROBB_ERROR_INVALID_FILE;
    saved->version = hairobb__get32(in + HAIROBB__AT_VERSION);
    if (saved->version < HAIROBB__SAVE_VERSION_OLDEST || saved->version > HAIROBB__SAVE_VERSION ||
        hairobb__get32(in + HAIROBB__AT_BYTE_ORDER) != HAIROBB__SAVE_BYTE_ORDER || hairobb__get32(in + HAIROBB__AT_WIDTH) != HAIROBB__W)
        return HAIROBB_ERROR_UNSUPPORTED;
    saved->node_bytes = hairobb__get64(in + HAIROBB__AT_NODE_BYTES);
    saved->leaf_prim_count = hairobb__get64(in + HAIROBB__AT_LEAF_PRIMS);
    if (saved->node_bytes > size - HAIROBB__SAVE_HEADER - 8 || saved->leaf_prim_count > (size - HAIROBB__SAVE_HEADER - 8) / sizeof(uint32_t))
        return HAIROBB_ERROR_INVALID_FILE;
    saved->leaf_bytes = hairobb__saved_leaf_bytes((size_t)saved->leaf_prim_count);
    flags = hairobb__get32(in + HAIROBB__AT_FLAGS);
    /* no overflow: below size */
    saved->range_bytes = flags & HAIROBB__SAVE_RANGES ? 2 * sizeof(float) * (size_t)saved->leaf_prim_count : 0;
    saved->groups = 0;
    saved->shapes_at = 0;
    if (flags > (saved->version >= 3u ? HAIROBB__SAVE_RANGES | HAIROBB__SAVE_GROUPS | HAIROBB__SAVE_SHAPES : HAIROBB__SAVE_RANGES) ||
        ((flags & HAIROBB__SAVE_SHAPES) && !(flags & HAIROBB__SAVE_GROUPS)) ||
        saved->leaf_bytes + saved->range_bytes > size - HAIROBB__SAVE_HEADER - 8 - (size_t)saved->node_bytes)
        return HAIROBB_ERROR_INVALID_FILE;
    saved->group_at = HAIROBB__SAVE_HEADER + (size_t)saved->node_bytes + saved->leaf_bytes + saved->range_bytes;
    if (flags & HAIROBB__SAVE_GROUPS) {   /* its count first, then its size must add up too */
        if (size - 8 - saved->group_at < 8) return HAIROBB_ERROR_INVALID_FILE;
        saved->groups = hairobb__get64(in + saved->group_at);
        if (saved->groups == 0 || saved->groups > (size - 8 - saved->group_at) / 12 ||
            hairobb__saved_group_bytes(saved->groups) + (flags & HAIROBB__SAVE_SHAPES ? hairobb__saved_shape_bytes(saved->groups) : 0) !=
                size - 8 - saved->group_at)
            return HAIROBB_ERROR_INVALID_FILE;
        if (flags & HAIROBB__SAVE_SHAPES) {   /* each a shape, the padding zero */
            saved->shapes_at = saved->group_at + hairobb__saved_group_bytes(saved->groups);
            for (i = 0; i < hairobb__saved_shape_bytes(saved->groups); ++i)
                if (in[saved->shapes_at + i] > (i < saved->groups ? (unsigned)HAIROBB_SHAPE_ROUND : 0u)) return HAIROBB_ERROR_INVALID_FILE;
        }
    } else if (saved->group_at != size - 8) {
        return HAIROBB_ERROR_INVALID_FILE;
    }
    if (hairobb__get64(in + size - 8) != hairobb__save_checksum(in, size)) return HAIROBB_ERROR_INVALID_FILE;
    saved->basis = hairobb__get32(in + HAIROBB__AT_BASIS);
    precision = hairobb__get32(in + HAIROBB__AT_PRECISION);
    pieces = hairobb__get32(in + HAIROBB__AT_PIECES);
    layout = hairobb__get32(in + HAIROBB__AT_LAYOUT);
    max_leaf = hairobb__get32(in + HAIROBB__AT_MAX_LEAF);
    policy = hairobb__get32(in + HAIROBB__AT_POLICY);
    saved->segments = hairobb__get64(in + HAIROBB__AT_SEGMENTS);
    if (saved->basis > HAIROBB_BASIS_LINEAR || precision > HAIROBB_PRECISION_PIECES || pieces < 1 || pieces > HAIROBB__MAX_PIECES ||
        layout < HAIROBB_OBB_PER_CHILD || layout > HAIROBB_OBB_COMPRESSED_PER_CHILD || max_leaf < 1 || max_leaf > HAIROBB__MAX_LEAF ||
        policy > HAIROBB_NODES_OBB_ONLY ||
        (shape_word = hairobb__get32(in + HAIROBB__AT_SHAPE)) > (HAIROBB_SHAPE_ROUND | HAIROBB__SAVE_CAPS | HAIROBB__SAVE_CULL) ||
        (shape = shape_word & 0xffu) > HAIROBB_SHAPE_ROUND || (shape != HAIROBB_SHAPE_ROUND && shape_word != shape) ||
        (shape == HAIROBB_SHAPE_ROUND && precision == HAIROBB_PRECISION_PIECES) ||
        saved->segments == 0 || saved->leaf_prim_count == 0 || saved->node_bytes % 16 != 0 ||
        (saved->shapes_at && shape != HAIROBB_SHAPE_ROUND))   /* groups of both shapes build as round */
        return HAIROBB_ERROR_INVALID_FILE;
    for (i = HAIROBB__SAVE_HEADER + (size_t)saved->node_bytes + sizeof(uint32_t) * (size_t)saved->leaf_prim_count;
         i < HAIROBB__SAVE_HEADER + (size_t)saved->node_bytes + saved->leaf_bytes; ++i)
        if (in[i] != 0) return HAIROBB_ERROR_INVALID_FILE;
    for (k = 0; k < 3; ++k) {
        float lo, hi;
        memcpy(&lo, in + HAIROBB__AT_BOUNDS + 4 * k, sizeof lo);
        memcpy(&hi, in + HAIROBB__AT_BOUNDS + 12 + 4 * k, sizeof hi);
        if (!(lo <= hi) || !(fabsf(lo) <= FLT_MAX) || !(fabsf(hi) <= FLT_MAX)) return HAIROBB_ERROR_INVALID_FILE;
    }
    saved->steps = hairobb__get32(in + HAIROBB__AT_TIME_STEPS);
    if (saved->steps == 1 || saved->steps > HAIROBB__MAX_TIME_STEPS || (saved->steps && saved->basis == HAIROBB_BASIS_HERMITE))
        return HAIROBB_ERROR_INVALID_FILE;
    saved->tree.precision = (hairobb_precision)precision;
    saved->tree.policy = (hairobb_node_policy)policy;
    saved->tree.obb_layout = (hairobb_obb_layout)layout;
    saved->tree.max_leaf_size = max_leaf;
    saved->tree.pieces = pieces;
    saved->tree.shape = (hairobb_shape)shape;
    saved->tree.end_caps = (shape_word & HAIROBB__SAVE_CAPS) != 0;
    saved->tree.cull_back_faces = (shape_word & HAIROBB__SAVE_CULL) != 0;
    return HAIROBB_OK;
}

/* The saved tree into the BVH: node memory, the leaves' ids (each below
   segment_count) and u ranges (inside [0, 1]), then the walk of the whole
   tree (hairobb__check_tree), which counts its nodes into *stats.
   OUT_OF_MEMORY or INVALID_FILE; what was allocated is the BVH's. */
static hairobb_result hairobb__load_tree(hairobb_bvh *bvh, const unsigned char *in, const hairobb__saved *saved,
                                         size_t segment_count, hairobb_stats *stats)
{
    void *user = bvh->allocator_user;
    hairobb__tree_check check;
    hairobb_result result = HAIROBB_ERROR_OUT_OF_MEMORY;
    unsigned char *named = NULL;
    size_t i;
    memset(&check, 0, sizeof check);
    if (saved->node_bytes) {
        unsigned char *allocation = HAIROBB__CAST(unsigned char *, hairobb__malloc_large((size_t)saved->node_bytes + 64, user));
        if (!allocation) goto done;
        bvh->node_allocation = allocation;
        bvh->nodes = hairobb__align64(allocation);
        bvh->node_bytes = (size_t)saved->node_bytes;
        memcpy(bvh->nodes, in + HAIROBB__SAVE_HEADER, bvh->node_bytes);
        check.reached = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(bvh->node_bytes / 128 + 1, user));
        if (!check.reached) goto done;
        memset(check.reached, 0, bvh->node_bytes / 128 + 1);
    }
    bvh->leaf_prims = HAIROBB__CAST(uint32_t *, hairobb__malloc_large(sizeof(uint32_t) * (size_t)saved->leaf_prim_count, user));
    if (!bvh->leaf_prims) goto done;
    bvh->leaf_prim_count = (size_t)saved->leaf_prim_count;
    memcpy(bvh->leaf_prims, in + HAIROBB__SAVE_HEADER + bvh->node_bytes, sizeof(uint32_t) * bvh->leaf_prim_count);
    bvh->root = hairobb__get64(in + HAIROBB__AT_ROOT);
    if (saved->range_bytes) {
        /* u ranges inside [0, 1] (hairobb_refit clips the segments to them) */
        bvh->leaf_ranges = HAIROBB__CAST(float *, hairobb__malloc_large(saved->range_bytes, user));
        if (!bvh->leaf_ranges) goto done;
        memcpy(bvh->leaf_ranges, in + HAIROBB__SAVE_HEADER + bvh->node_bytes + saved->leaf_bytes, saved->range_bytes);
    }
    /* every segment named by some leaf, as in every built tree (the copy reads each one's points from one) */
    named = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(segment_count / 8 + 1, user));
    if (!named) goto done;
    memset(named, 0, segment_count / 8 + 1);
    result = HAIROBB_ERROR_INVALID_FILE;
    for (i = 0; i < bvh->leaf_prim_count; ++i) {
        if (bvh->leaf_prims[i] >= segment_count) goto done;
        named[bvh->leaf_prims[i] >> 3] |= (unsigned char)(1u << (bvh->leaf_prims[i] & 7u));
        if (bvh->leaf_ranges && !(bvh->leaf_ranges[2 * i] >= 0.0f && bvh->leaf_ranges[2 * i] <= bvh->leaf_ranges[2 * i + 1] &&
                                  bvh->leaf_ranges[2 * i + 1] <= 1.0f))
            goto done;
    }
    for (i = 0; i < segment_count; ++i)
        if (!(named[i >> 3] >> (i & 7u) & 1u)) goto done;
    check.nodes = bvh->nodes;
    check.node_bytes = bvh->node_bytes;
    check.leaf_prim_count = bvh->leaf_prim_count;
    check.inner_types = hairobb__layout_types(saved->tree.obb_layout, saved->tree.policy, saved->steps != 0);
    check.max_leaf = saved->tree.max_leaf_size;
    if (hairobb__check_tree(&check, bvh->root, 0) && check.next_leaf == check.leaf_prim_count &&
        check.reached_bytes == check.node_bytes) {
        *stats = check.stats;
        result = HAIROBB_OK;
    }
done:
    if (check.reached) HAIROBB_FREE(check.reached, user);
    if (named) HAIROBB_FREE(named, user);
    return result;
}

/* hairobb_load, and hairobb_load_groups over the groups' concatenation
   (groups: 1; the saved groups' count and section left in *saved) */
static hairobb_result hairobb__load(const void *buffer, size_t size, const float *vertices, size_t vertex_count, const uint32_t *indices,
                                    size_t segment_count, const hairobb_build_options *options, int groups, hairobb__saved *saved_out,
                                    hairobb_bvh **out)
{
    const unsigned char *in = HAIROBB__CAST(const unsigned char *, buffer);
    hairobb_build_options opt;
    hairobb__saved saved;
    memset(&saved, 0, sizeof saved);   /* every field is read only once the header checked it; gcc -O1 cannot tell */
    hairobb_stats stats;
    hairobb_result result;
    hairobb_simd simd;
    hairobb_bvh *bvh;
    unsigned steps;
    int k;

    if (out) *out = NULL;
    memset(&opt, 0, sizeof opt);   /* read below even where the options were refused */
    result = hairobb__resolve_options(options, HAIROBB__FOR_LOAD, &opt);
    if (!out || !in || (!vertices && opt.time_steps < 2) || !indices || segment_count == 0) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (result == HAIROBB_OK) result = hairobb__choose_simd(opt.simd, &simd);
    if (result == HAIROBB_OK) result = hairobb__read_saved(in, size, &saved);
    if (result == HAIROBB_OK && (saved.basis != (uint32_t)opt.basis || saved.segments != (uint64_t)segment_count ||
                                 saved.steps != (opt.time_steps < 2 ? 0u : opt.time_steps) || (saved.groups && !groups)))
        result = HAIROBB_ERROR_MISMATCH;
    *saved_out = saved;
    if (result == HAIROBB_OK) result = hairobb__validate_hair(&opt, &vertices, vertex_count, indices, segment_count, &steps);
    if (result != HAIROBB_OK) return result;

    bvh = HAIROBB__CAST(hairobb_bvh *, HAIROBB_MALLOC(sizeof *bvh, opt.allocator_user));
    if (!bvh) return HAIROBB_ERROR_OUT_OF_MEMORY;
    memset(bvh, 0, sizeof *bvh);
    bvh->allocator_user = opt.allocator_user;
    result = HAIROBB_ERROR_OUT_OF_MEMORY;
    if (!hairobb__take_hair(bvh, &opt, vertices, vertex_count, indices, segment_count, steps)) goto failed;
    if (opt.verify_hair == HAIROBB_ON &&
        (hairobb__get64(in + HAIROBB__AT_VERTICES) != (uint64_t)hairobb__traced_vertex_count(bvh) ||
         hairobb__get64(in + HAIROBB__AT_HAIR_HASH) != hairobb__traced_hash(bvh, saved.version))) {
        result = HAIROBB_ERROR_MISMATCH;
        goto failed;
    }
    result = hairobb__load_tree(bvh, in, &saved, segment_count, &stats);
    if (result != HAIROBB_OK) goto failed;
    for (k = 0; k < 3; ++k) {
        memcpy(&bvh->lower[k], in + HAIROBB__AT_BOUNDS + 4 * k, sizeof(float));
        memcpy(&bvh->upper[k], in + HAIROBB__AT_BOUNDS + 12 + 4 * k, sizeof(float));
    }
    hairobb__set_settings(bvh, &opt, simd, &saved.tree);
    hairobb__set_stats(bvh, &stats);
    result = hairobb__copy_points(bvh);
    if (result != HAIROBB_OK) goto failed;
    if (bvh->copy_points && bvh->point_basis != HAIROBB_BASIS_BEZIER) bvh->vertices = NULL, bvh->tangents = NULL;
    *out = bvh;
    return HAIROBB_OK;

failed:
    hairobb_free(bvh);
    return result;
}

HAIROBB_DEF hairobb_result hairobb_load(const void *buffer, size_t size, const float *vertices, size_t vertex_count,
                                        const uint32_t *indices, size_t segment_count, const hairobb_build_options *options,
                                        hairobb_bvh **out)
{
    hairobb__saved saved;
    return hairobb__load(buffer, size, vertices, vertex_count, indices, segment_count, options, 0, &saved, out);
}

HAIROBB_DEF hairobb_result hairobb_load_groups(const void *buffer, size_t size, const hairobb_group *groups, size_t group_count,
                                               const hairobb_build_options *options, hairobb_bvh **out)
{
    hairobb_build_options opt = options ? *options : hairobb_default_options();
    hairobb_bvh scratch;
    hairobb__saved saved;
    hairobb_result result;
    if (out) *out = NULL;
    if (!out || !buffer) return HAIROBB_ERROR_INVALID_ARGUMENT;
    result = hairobb__take_groups(groups, group_count, &opt, &scratch);
    if (result != HAIROBB_OK) return result;
    memset(&saved, 0, sizeof saved);
    result = hairobb__load(buffer, size, scratch.group_vertices, scratch.vertex_count, scratch.group_indices, scratch.segment_count, &opt,
                           1, &saved, out);
    if (result == HAIROBB_OK) {   /* the saved groups' sizes: a one-group file is one group */
        const unsigned char *in = HAIROBB__CAST(const unsigned char *, buffer) + saved.group_at;
        size_t first_bytes = (((size_t)saved.groups + 1) * sizeof(uint32_t) + 7) & ~(size_t)7, g;
        if (saved.groups ? saved.groups != (uint64_t)group_count : group_count != 1) result = HAIROBB_ERROR_MISMATCH;
        for (g = 0; result == HAIROBB_OK && saved.groups && g <= group_count; ++g)
            if (hairobb__get32(in + 8 + 4 * g) != scratch.group_first[g] ||
                hairobb__get64(in + 8 + first_bytes + 8 * g) != (uint64_t)scratch.vertex_first[g])
                result = HAIROBB_ERROR_MISMATCH;
        /* the saved shapes: a group with segments that asks for its own
           must have it (an empty one's is moot, so as asked) */
        for (g = 0; result == HAIROBB_OK && g < group_count; ++g) {
            unsigned asked = scratch.group_shape[g];
            hairobb_shape shape = saved.shapes_at ? (hairobb_shape)((const unsigned char *)buffer)[saved.shapes_at + g] : (*out)->shape;
            if (asked != HAIROBB_GROUP_SHAPE_OPTIONS &&
                asked != (shape == HAIROBB_SHAPE_ROUND ? (unsigned)HAIROBB_GROUP_SHAPE_ROUND : (unsigned)HAIROBB_GROUP_SHAPE_RIBBON)) {
                if (scratch.group_first[g + 1] > scratch.group_first[g]) result = HAIROBB_ERROR_MISMATCH;
                shape = asked == HAIROBB_GROUP_SHAPE_ROUND ? HAIROBB_SHAPE_ROUND : HAIROBB_SHAPE_RIBBON;
            }
            scratch.group_shape[g] = (unsigned char)shape;
        }
        if (result == HAIROBB_OK) result = hairobb__group_round_bits(&scratch);
        /* shapes are saved only where groups with segments mix them */
        if (result == HAIROBB_OK && saved.shapes_at && !scratch.round_bits) result = HAIROBB_ERROR_INVALID_FILE;
    }
    if (result != HAIROBB_OK) {
        hairobb_free(*out);
        *out = NULL;
        hairobb__free_groups(&scratch);
        return result;
    }
    hairobb__attach_groups(*out, &scratch);
    return HAIROBB_OK;
}

#ifndef HAIROBB_NO_STDIO
HAIROBB_DEF hairobb_result hairobb_save_file(const hairobb_bvh *bvh, const char *path)
{
    size_t size = hairobb_save_size(bvh);
    unsigned char *data;
    hairobb_result result;
    FILE *file;
    if (!bvh || !path) return HAIROBB_ERROR_INVALID_ARGUMENT;
    data = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC(size, bvh->allocator_user));
    if (!data) return HAIROBB_ERROR_OUT_OF_MEMORY;
    result = hairobb_save(bvh, data, size);
    if (result == HAIROBB_OK) {
        file = fopen(path, "wb");
        if (!file) {
            result = HAIROBB_ERROR_IO;
        } else {
            if (fwrite(data, 1, size, file) != size) result = HAIROBB_ERROR_IO;
            if (fclose(file) != 0) result = HAIROBB_ERROR_IO;
        }
    }
    HAIROBB_FREE(data, bvh->allocator_user);
    return result;
}

HAIROBB_DEF hairobb_result hairobb_load_file(const char *path,
                                             const float *vertices, size_t vertex_count,
                                             const uint32_t *indices, size_t segment_count,
                                             const hairobb_build_options *options, hairobb_bvh **out)
{
    void *user = options ? options->allocator_user : NULL;
    unsigned char header[HAIROBB__SAVE_HEADER], *data;
    hairobb_result result = HAIROBB_OK;
    FILE *file;
    uint64_t length = 0;
    if (out) *out = NULL;
    if (!path || !out) return HAIROBB_ERROR_INVALID_ARGUMENT;
    file = fopen(path, "rb");
    if (!file) return HAIROBB_ERROR_IO;
    if (fread(header, 1, sizeof header, file) != sizeof header)
        result = ferror(file) ? HAIROBB_ERROR_IO : HAIROBB_ERROR_INVALID_FILE;   /* a directory, or too short */
    else if (!hairobb__file_length(file, &length))
        result = HAIROBB_ERROR_IO;
    else if (memcmp(header, hairobb__save_magic, sizeof hairobb__save_magic) == 0 &&
             hairobb__get32(header + HAIROBB__AT_VERSION) >= HAIROBB__SAVE_VERSION_OLDEST &&
             hairobb__get32(header + HAIROBB__AT_VERSION) <= HAIROBB__SAVE_VERSION &&
             hairobb__get32(header + HAIROBB__AT_BYTE_ORDER) == HAIROBB__SAVE_BYTE_ORDER &&
             hairobb__get32(header + HAIROBB__AT_WIDTH) == HAIROBB__W &&
             (hairobb__get64(header + HAIROBB__AT_NODE_BYTES) > length ||
              hairobb__get64(header + HAIROBB__AT_LEAF_PRIMS) > length / sizeof(uint32_t) ||
              HAIROBB__SAVE_HEADER + hairobb__get64(header + HAIROBB__AT_NODE_BYTES) +
                      ((sizeof(uint32_t) * hairobb__get64(header + HAIROBB__AT_LEAF_PRIMS) + 7) & ~(uint64_t)7) + 8 !=
                  (uint64_t)length))
        result = HAIROBB_ERROR_INVALID_FILE;   /* sizes that disagree with the file's: before any large allocation */
    else if (length > (uint64_t)((size_t)-1))
        result = HAIROBB_ERROR_TOO_LARGE;
    if (result == HAIROBB_OK) {
        data = HAIROBB__CAST(unsigned char *, HAIROBB_MALLOC((size_t)length, user));
        if (!data)
            result = HAIROBB_ERROR_OUT_OF_MEMORY;
        else if (fread(data, 1, (size_t)length, file) != (size_t)length)
            result = HAIROBB_ERROR_IO;
        else
            result = hairobb_load(data, (size_t)length, vertices, vertex_count, indices, segment_count, options, out);
        if (data) HAIROBB_FREE(data, user);
    }
    fclose(file);
    return result;
}
#endif

/* ------------------------------------------------------------------------ */
/* >>rays  Rays: what every traversal path reads                            */
/* ------------------------------------------------------------------------ */

/* A ray prepared for slab tests against boxes in one frame. */
typedef struct hairobb__slab_ray {
    float org[3];
    float rdir[3];              /* 1/dir, finite */
    /* floats from a node's lower[0] to the plane entered (near) and left
       (far) on each axis: the upper plane is entered where rdir < 0 */
    int near_plane[3], far_plane[3];
} hairobb__slab_ray;

/* A segment's control points in ray space: x, y across the ray, z along it. */
typedef struct hairobb__ray_curve {
    float x[4], y[4], z[4], r[4];
} hairobb__ray_curve;

/* Everything one ray needs, computed once per ray. */
/* A filter is shown each crossing once: candidates it ignored are kept
   (the last HAIROBB__SHOWN, and apart the last HAIROBB__SHOWN within
   2^-10 of a segment's end, which a joint's other segment may find after
   many others), and one found again (the same segment at the same u, or
   the two segments of a joint at its point, on the same side of a tube:
   its entry and exit are two crossings however close) is not shown. */
#define HAIROBB__SHOWN 8
/* An instance of a scene as the tracing reads it (SCENES, >>scene). */
typedef struct hairobb__placed {
    const hairobb_bvh *bvh;
    float to_world[12], to_object[12];   /* affine maps, 3 rows of 4 */
    uint32_t mask;                       /* 0 given: every bit */
    void *user;
    float lower[3], upper[3];            /* world box */
} hairobb__placed;

/* A ray's state while it is traced, in rooms by how long each part lives:
   call (set once a call: filters, masks, the instance), line (the ray
   itself; tfar shrinks as hits are found), best (the nearest hit so far),
   shown (what the filters were shown and ignored) and skip (a secondary
   ray's segment left). What a segment's test shares with the functions it
   calls is theirs, passed as an argument (hairobb__ribbon_segment,
   hairobb__tube_segment). */
typedef struct hairobb__ray_call {
    int filtering;              /* a build-time or per-call filter is set */
    int any_hit;                /* occluded1 */
    hairobb_filter_fn hit_filter, call_filter;   /* the BVH's for this kind of call; the call's */
    void *hit_filter_user, *call_filter_user;
    const hairobb_bvh *bvh;     /* set with a hit filter only: what it is called with */
    const hairobb_ray *ray;     /* the caller's */
    const hairobb__placed *placed;   /* scenes: the instance traced (its hits go to world space); else NULL */
    uint32_t instance_id;
    int cull_back_faces;        /* tubes: back_faces OFF */
    /* groups (>>groups): the ray's mask, and whether it excludes some group
       (then each hit's group is looked up) */
    uint32_t ray_mask;
    int group_masked;
    const hairobb_bvh *bvh_groups;    /* the BVH traced, where group_masked */
} hairobb__ray_call;

typedef struct hairobb__ray_line {
    float org[3], dir[3];
    float tnear, tfar;          /* tfar shrinks to the nearest hit so far */
    float time;                 /* the ray's, for motion-blurred BVHs */
    hairobb__slab_ray world;    /* for AABB nodes */
    float frame[9];             /* rows x, y, z of ray space; z = dir/|dir| */
    float dir_length, inv_dir_length;
} hairobb__ray_line;

typedef struct hairobb__ray_best {
    uint32_t prim;              /* HAIROBB_INVALID_ID until a hit is taken */
    float u;
    hairobb__ray_curve curve;   /* prim in ray space (intersect1): for its attributes */
    const float *points;        /* its world points where they stay put (the copy, or Bezier in place); else NULL */
    int cap;                    /* tubes: the hit taken is on an end cap */
} hairobb__ray_best;

typedef struct hairobb__ray_shown {
    int count[2];               /* candidates the filters ignored: all, those at ends; the last HAIROBB__SHOWN of each: */
    uint32_t prim[2][HAIROBB__SHOWN];
    float u[2][HAIROBB__SHOWN], t[2][HAIROBB__SHOWN];
    int exit[2][HAIROBB__SHOWN];   /* tubes: the crossing left the fibre (outward Ng along the ray) */
} hairobb__ray_shown;

/* secondary rays: hits before t on the segment left and on those joined
   to its ends (positions of its first and last control point) are
   ignored; t = 0 for other rays */
typedef struct hairobb__ray_skip {
    float t;
    float sheet;                /* tubes: the sheet skipped (+1 entries, -1 exits); 0 ribbons: every hit */
    uint32_t prim;
    float first[3], last[3];
    int active;                 /* tubes: set while a skipped segment is tested */
} hairobb__ray_skip;

typedef struct hairobb__ray_state {
    hairobb__ray_call call;
    hairobb__ray_line line;
    hairobb__ray_best best;
    hairobb__ray_shown shown;
    hairobb__ray_skip skip;
} hairobb__ray_state;

#define HAIROBB__TINY_DIR 1e-18f
/* Slab distances carry rounding from the ray transform; widening the far end
   by a few ulps keeps the test conservative (after Ize 2013). */
#define HAIROBB__FAR_SCALE (1.0f + 4.0f * FLT_EPSILON)
/* A segment's cull against the planes z = tnear, tfar is widened by this
   much of its largest |z| (hairobb__intersect_segment). */
#define HAIROBB__Z_SLACK (1.0f / 65536.0f)

/* org and dir given in the slab frame; zero direction components become
   +-tiny, so 1/dir stays finite for rays parallel to a slab. The upper
   plane is entered first where 1/dir < 0, that is, where its sign bit is
   set (1/dir is never -0 or NaN for a finite dir). */
HAIROBB__INLINE void hairobb__slab_setup(hairobb__slab_ray *slab, const float org[3], const float dir[3])
{
    int k, upper_first;
#if HAIROBB__SSE
    /* the three axes at once */
    float rdir[4];
    __m128 d = _mm_setr_ps(dir[0], dir[1], dir[2], 1.0f), sign_bit = _mm_set1_ps(-0.0f);
    __m128 tiny = _mm_set1_ps(HAIROBB__TINY_DIR);
    __m128 tiny_lanes = _mm_cmplt_ps(_mm_andnot_ps(sign_bit, d), tiny);
    d = _mm_or_ps(_mm_andnot_ps(tiny_lanes, d), _mm_and_ps(tiny_lanes, _mm_or_ps(_mm_and_ps(d, sign_bit), tiny)));
    d = _mm_div_ps(_mm_set1_ps(1.0f), d);
    _mm_storeu_ps(rdir, d);
    upper_first = _mm_movemask_ps(d);
    memcpy(slab->rdir, rdir, sizeof slab->rdir);
#else
    upper_first = 0;
    for (k = 0; k < 3; ++k) {
        float d = fabsf(dir[k]) < HAIROBB__TINY_DIR ? (signbit(dir[k]) ? -HAIROBB__TINY_DIR : HAIROBB__TINY_DIR) : dir[k];
        slab->rdir[k] = 1.0f / d;
        upper_first |= (signbit(slab->rdir[k]) ? 1 : 0) << k;
    }
#endif
    memcpy(slab->org, org, sizeof slab->org);
    for (k = 0; k < 3; ++k) {
        int upper = (upper_first >> k) & 1;
        slab->near_plane[k] = (upper ? 3 * HAIROBB__W : 0) + k * HAIROBB__W;
        slab->far_plane[k] = (upper ? 0 : 3 * HAIROBB__W) + k * HAIROBB__W;
    }
}

static int hairobb__ray_setup(hairobb__ray_state *rs, const hairobb_bvh *bvh, const hairobb_ray *ray)
{
    int k;
    float unit[3];
    rs->call.filtering = 0;
    rs->call.bvh = bvh;
    rs->call.ray = ray;
    memcpy(rs->line.org, ray->org, sizeof rs->line.org);
    memcpy(rs->line.dir, ray->dir, sizeof rs->line.dir);
    hairobb__slab_setup(&rs->line.world, ray->org, ray->dir);
    rs->line.tnear = ray->tnear;
    rs->line.tfar = ray->tfar;
    rs->line.time = ray->time;
    rs->best.prim = HAIROBB_INVALID_ID;
    rs->best.points = NULL;
    rs->best.u = 0.0f;
    rs->skip.t = 0.0f;
    rs->skip.sheet = 0.0f;
    rs->skip.active = 0;
    rs->best.cap = 0;
    rs->call.cull_back_faces = bvh->cull_back_faces;
    rs->call.placed = NULL;
    rs->call.instance_id = HAIROBB_INVALID_ID;
    rs->call.group_masked = 0;   /* ray_mask and bvh_groups are read only where it is set (hairobb__set_filters) */
    rs->line.dir_length = sqrtf(hairobb__dot3(ray->dir, ray->dir));
    if (!(rs->line.dir_length > 0.0f) || !(rs->line.dir_length < INFINITY) || !(rs->line.tnear <= rs->line.tfar)) return 0;
    if (bvh->time_steps && !(rs->line.time >= 0.0f && rs->line.time <= 1.0f)) return 0;   /* NaN too */
    rs->line.inv_dir_length = 1.0f / rs->line.dir_length;
    for (k = 0; k < 3; ++k) unit[k] = ray->dir[k] * rs->line.inv_dir_length;
    hairobb__frame_from_direction(unit, rs->line.frame);
    return 1;
}

/* The same curve in power form, a[0] + a[1] u + a[2] u^2 + a[3] u^3: the
   root finder evaluates it many times, Horner's rule makes that cheap.
   Lanes x, y, z, r of each coefficient, so that one 4-wide Horner step
   takes all four; d holds 2 a[2], 3 a[3], 6 a[3], the derivatives'. */
typedef struct hairobb__ray_poly {
    float a[4][4];
    float d[3][4];
} hairobb__ray_poly;

/* Instrumented builds (tests/test_conservative.c) see each segment of each
   leaf a ray reaches; nonzero skips its intersection, so no hit shortens
   the ray and the traversal reaches every leaf the ray's boxes lead to. */
#ifndef HAIROBB__LEAF_VISIT
#define HAIROBB__LEAF_VISIT(rs, prim) 0
#endif

/* Instrumented builds (the bench's profile, bench/profile.sh) count the
   traversal's work per ray: node (a node's children tested), leaf,
   segment (a segment's first, conservative test) and segment_passed (the
   segments that pass it and go on to the exact test). */
#ifndef HAIROBB__COUNT
#define HAIROBB__COUNT(what) ((void)0)
#endif

/* A ray leaving the hit `from` (NULL: none): the band it skips is twice the
   segment's largest radius, the ribbon's reach whichever way it faces the
   new ray, plus 8 float ulps of the origin for the rounding of the hit
   point the caller computed. */
static int hairobb__ray_setup_from(hairobb__ray_state *rs, const hairobb_bvh *bvh, const hairobb_hit *from,
                                   const hairobb_ray *ray)
{
    const float *cp;
    float max_r, magnitude, scratch[16];
    uint32_t prim;
    if (!hairobb__ray_setup(rs, bvh, ray)) return 0;
    if (!from) return 1;
    prim = from->prim_id;
    if (bvh->group_first) {   /* the group's segment in the concatenation */
        if (from->group_id >= bvh->group_count || prim >= bvh->group_first[from->group_id + 1] - bvh->group_first[from->group_id])
            return 1;
        prim += bvh->group_first[from->group_id];
    }
    if (prim >= bvh->segment_count) return 1;
    cp = hairobb__segment_points(bvh, prim, rs->line.time, scratch);
    max_r = hairobb__maxf(hairobb__maxf(cp[3], cp[7]), hairobb__maxf(cp[11], cp[15]));
    magnitude = hairobb__maxf(hairobb__maxf(fabsf(ray->org[0]), fabsf(ray->org[1])), fabsf(ray->org[2]));
    rs->skip.t = (2.0f * max_r + magnitude * (8.0f * FLT_EPSILON)) * rs->line.inv_dir_length;
    /* A tube does not turn to face the new ray. A ray that starts on it,
       its origin a rounding inside or outside, can meet the sheet it
       leaves through at once: a ray going out (along the outward normal
       `from` gives) an exit, a ray going in an entry. Only that sheet is
       skipped within the band, so a ray going in finds the fibre's far
       side. */
    if (hairobb__is_tube(bvh, prim)) rs->skip.sheet = hairobb__dot3(ray->dir, from->Ng) > 0.0f ? -1.0f : 1.0f;
    rs->skip.prim = prim;
    memcpy(rs->skip.first, cp, sizeof rs->skip.first);
    memcpy(rs->skip.last, cp + 12, sizeof rs->skip.last);
    return 1;
}

#endif /* !HAIROBB__KERNEL_PASS */

/* ======================================================================== */
/* >>kernels  SIMD, traversal and ray/curve intersection. Compiled for      */
/* the instruction sets the compiler targets, and again for AVX2 with every */
/* name suffixed _avx2 where HAIROBB__DISPATCH (see "Runtime dispatch").    */
/* ======================================================================== */
/* ------------------------------------------------------------------------ */
/* >>simd  4 or 8 lanes for nodes, 8 for curve points (inline, as a build   */
/* uses only some). Each operation has a plain C twin with the same         */
/* rounding and NaN rule (min(a,b) is a < b ? a : b, as SSE's minps), so    */
/* every path gives the same answers.                                       */
/* ------------------------------------------------------------------------ */
/* The number of set bits (the traversal's): the popcnt instruction in the
   AVX2 copy and wherever the target has one; on baseline x86-64 a few
   shifts and masks, where gcc's __builtin_popcount is a call to libgcc. */
HAIROBB__INLINE int hairobb__bit_count(unsigned bits)
{
#if (defined(__GNUC__) || defined(__clang__)) && (HAIROBB__AVX2 || defined(__POPCNT__) || !(defined(__x86_64__) || defined(__i386__)))
    return __builtin_popcount(bits);
#else
    bits = bits - ((bits >> 1) & 0x55555555u);
    bits = (bits & 0x33333333u) + ((bits >> 2) & 0x33333333u);
    return (int)((((bits + (bits >> 4)) & 0x0f0f0f0fu) * 0x01010101u) >> 24);
#endif
}

#if HAIROBB__SSE
typedef __m128 hairobb__v4;
static inline hairobb__v4 hairobb__v4_load(const float *p) { return _mm_loadu_ps(p); }
static inline hairobb__v4 hairobb__v4_set1(float x) { return _mm_set1_ps(x); }
static inline hairobb__v4 hairobb__v4_set3(float x, float y, float z) { return _mm_setr_ps(x, y, z, 0.0f); }
static inline hairobb__v4 hairobb__v4_add(hairobb__v4 a, hairobb__v4 b) { return _mm_add_ps(a, b); }
static inline hairobb__v4 hairobb__v4_sub(hairobb__v4 a, hairobb__v4 b) { return _mm_sub_ps(a, b); }
static inline hairobb__v4 hairobb__v4_mul(hairobb__v4 a, hairobb__v4 b) { return _mm_mul_ps(a, b); }
static inline hairobb__v4 hairobb__v4_div(hairobb__v4 a, hairobb__v4 b) { return _mm_div_ps(a, b); }
static inline hairobb__v4 hairobb__v4_min(hairobb__v4 a, hairobb__v4 b) { return _mm_min_ps(a, b); }
static inline hairobb__v4 hairobb__v4_max(hairobb__v4 a, hairobb__v4 b) { return _mm_max_ps(a, b); }
static inline int hairobb__v4_le_bits(hairobb__v4 a, hairobb__v4 b) { return _mm_movemask_ps(_mm_cmple_ps(a, b)); }
static inline int hairobb__v4_lt_bits(hairobb__v4 a, hairobb__v4 b) { return _mm_movemask_ps(_mm_cmplt_ps(a, b)); }
static inline void hairobb__v4_store(float *p, hairobb__v4 a) { _mm_storeu_ps(p, a); }
static inline hairobb__v4 hairobb__v4_abs(hairobb__v4 a) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), a); }
static inline hairobb__v4 hairobb__v4_sqrt(hairobb__v4 a) { return _mm_sqrt_ps(a); }
/* (a[k], a[k + 1], b[k], b[k + 1]) for k = 0, 1, 2 (moves only). */
static inline hairobb__v4 hairobb__v4_pairs(hairobb__v4 a, hairobb__v4 b, int k)
{
    return k == 0 ? _mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 1, 0)) :
           k == 1 ? _mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 1, 2, 1)) : _mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 2, 3, 2));
}
/* (a1, a2, a3, b0): each lane the one after it (moves only). */
static inline hairobb__v4 hairobb__v4_next(hairobb__v4 a, hairobb__v4 b)
{
    return _mm_shuffle_ps(a, _mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 3, 3)), _MM_SHUFFLE(2, 0, 2, 1));
}
/* Rows a..d become columns (moves only). */
static inline void hairobb__v4_transpose(hairobb__v4 *a, hairobb__v4 *b, hairobb__v4 *c, hairobb__v4 *d) { _MM_TRANSPOSE4_PS(*a, *b, *c, *d); }
/* max(max(a0, a2), max(a1, a3)) with max's NaN rule. */
static inline float hairobb__v4_hmax(hairobb__v4 a)
{
    __m128 t = _mm_max_ps(a, _mm_movehl_ps(a, a));
    return _mm_cvtss_f32(_mm_max_ss(t, _mm_shuffle_ps(t, t, 1)));
}
#if HAIROBB__SSE41
static inline hairobb__v4 hairobb__v4_from_bytes(const signed char *q)
{
    int packed;
    memcpy(&packed, q, sizeof packed);
    return _mm_cvtepi32_ps(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(packed)));
}
#else
/* SSE2: each byte unpacked with itself into the top of its 32-bit lane,
   then shifted down arithmetically: the integers SSE4.1's sign extension
   gives, in 4 instructions where 4 scalar conversions took about 15 */
static inline hairobb__v4 hairobb__v4_from_bytes(const signed char *q)
{
    int packed;
    __m128i bytes;
    memcpy(&packed, q, sizeof packed);
    bytes = _mm_cvtsi32_si128(packed);
    bytes = _mm_unpacklo_epi8(bytes, bytes);
    bytes = _mm_unpacklo_epi16(bytes, bytes);
    return _mm_cvtepi32_ps(_mm_srai_epi32(bytes, 24));
}
#endif
#elif HAIROBB__NEON
/* NEON: the same operations and rounding (no fused multiply-add); min and
   max as selects, for SSE's NaN rule (NEON's own vminq and vminnmq have
   other ones); the comparison masks gathered into bits as movemask does. */
typedef float32x4_t hairobb__v4;
static inline hairobb__v4 hairobb__v4_load(const float *p) { return vld1q_f32(p); }
static inline hairobb__v4 hairobb__v4_set1(float x) { return vdupq_n_f32(x); }
static inline hairobb__v4 hairobb__v4_set3(float x, float y, float z)
{
    float lanes[4];
    lanes[0] = x; lanes[1] = y; lanes[2] = z; lanes[3] = 0.0f;
    return vld1q_f32(lanes);
}
static inline hairobb__v4 hairobb__v4_add(hairobb__v4 a, hairobb__v4 b) { return vaddq_f32(a, b); }
static inline hairobb__v4 hairobb__v4_sub(hairobb__v4 a, hairobb__v4 b) { return vsubq_f32(a, b); }
static inline hairobb__v4 hairobb__v4_mul(hairobb__v4 a, hairobb__v4 b) { return vmulq_f32(a, b); }
static inline hairobb__v4 hairobb__v4_div(hairobb__v4 a, hairobb__v4 b) { return vdivq_f32(a, b); }
static inline hairobb__v4 hairobb__v4_min(hairobb__v4 a, hairobb__v4 b) { return vbslq_f32(vcltq_f32(a, b), a, b); }
static inline hairobb__v4 hairobb__v4_max(hairobb__v4 a, hairobb__v4 b) { return vbslq_f32(vcgtq_f32(a, b), a, b); }
static inline int hairobb__v4_mask_bits(uint32x4_t mask)
{
    static const uint32_t lane_bits[4] = {1u, 2u, 4u, 8u};
    return (int)vaddvq_u32(vandq_u32(mask, vld1q_u32(lane_bits)));
}
static inline int hairobb__v4_le_bits(hairobb__v4 a, hairobb__v4 b) { return hairobb__v4_mask_bits(vcleq_f32(a, b)); }
static inline int hairobb__v4_lt_bits(hairobb__v4 a, hairobb__v4 b) { return hairobb__v4_mask_bits(vcltq_f32(a, b)); }
static inline void hairobb__v4_store(float *p, hairobb__v4 a) { vst1q_f32(p, a); }
static inline hairobb__v4 hairobb__v4_abs(hairobb__v4 a) { return vabsq_f32(a); }
static inline hairobb__v4 hairobb__v4_sqrt(hairobb__v4 a) { return vsqrtq_f32(a); }
static inline hairobb__v4 hairobb__v4_pairs(hairobb__v4 a, hairobb__v4 b, int k)
{
    return k == 0 ? vcombine_f32(vget_low_f32(a), vget_low_f32(b)) :
           k == 1 ? vcombine_f32(vget_low_f32(vextq_f32(a, a, 1)), vget_low_f32(vextq_f32(b, b, 1))) :
                    vcombine_f32(vget_high_f32(a), vget_high_f32(b));
}
static inline hairobb__v4 hairobb__v4_next(hairobb__v4 a, hairobb__v4 b) { return vextq_f32(a, b, 1); }
static inline void hairobb__v4_transpose(hairobb__v4 *a, hairobb__v4 *b, hairobb__v4 *c, hairobb__v4 *d)
{
    float32x4_t ab0 = vtrn1q_f32(*a, *b), ab1 = vtrn2q_f32(*a, *b);   /* a0 b0 a2 b2, a1 b1 a3 b3 */
    float32x4_t cd0 = vtrn1q_f32(*c, *d), cd1 = vtrn2q_f32(*c, *d);
    *a = vreinterpretq_f32_f64(vtrn1q_f64(vreinterpretq_f64_f32(ab0), vreinterpretq_f64_f32(cd0)));
    *b = vreinterpretq_f32_f64(vtrn1q_f64(vreinterpretq_f64_f32(ab1), vreinterpretq_f64_f32(cd1)));
    *c = vreinterpretq_f32_f64(vtrn2q_f64(vreinterpretq_f64_f32(ab0), vreinterpretq_f64_f32(cd0)));
    *d = vreinterpretq_f32_f64(vtrn2q_f64(vreinterpretq_f64_f32(ab1), vreinterpretq_f64_f32(cd1)));
}
static inline float hairobb__v4_hmax(hairobb__v4 a)
{
    hairobb__v4 t = hairobb__v4_max(a, vextq_f32(a, a, 2));   /* max(a0, a2), max(a1, a3) */
    float t0 = vgetq_lane_f32(t, 0), t1 = vgetq_lane_f32(t, 1);
    return t0 > t1 ? t0 : t1;
}
static inline hairobb__v4 hairobb__v4_from_bytes(const signed char *q)
{
    int32_t packed;
    memcpy(&packed, q, sizeof packed);
    return vcvtq_f32_s32(vmovl_s16(vget_low_s16(vmovl_s8(vreinterpret_s8_s32(vdup_n_s32(packed))))));
}
#else
typedef struct hairobb__v4 { float f[4]; } hairobb__v4;
#define HAIROBB__V4_MAP(expr) hairobb__v4 r; int i; for (i = 0; i < 4; ++i) r.f[i] = (expr); return r
static inline hairobb__v4 hairobb__v4_load(const float *p) { HAIROBB__V4_MAP(p[i]); }
static inline hairobb__v4 hairobb__v4_set1(float x) { HAIROBB__V4_MAP(x); }
static inline hairobb__v4 hairobb__v4_set3(float x, float y, float z) { HAIROBB__V4_MAP(i == 0 ? x : i == 1 ? y : i == 2 ? z : 0.0f); }
static inline hairobb__v4 hairobb__v4_add(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] + b.f[i]); }
static inline hairobb__v4 hairobb__v4_sub(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] - b.f[i]); }
static inline hairobb__v4 hairobb__v4_mul(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] * b.f[i]); }
static inline hairobb__v4 hairobb__v4_div(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] / b.f[i]); }
static inline hairobb__v4 hairobb__v4_min(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] < b.f[i] ? a.f[i] : b.f[i]); }
static inline hairobb__v4 hairobb__v4_max(hairobb__v4 a, hairobb__v4 b) { HAIROBB__V4_MAP(a.f[i] > b.f[i] ? a.f[i] : b.f[i]); }
static inline hairobb__v4 hairobb__v4_from_bytes(const signed char *q) { HAIROBB__V4_MAP((float)q[i]); }
#undef HAIROBB__V4_MAP
static inline int hairobb__v4_le_bits(hairobb__v4 a, hairobb__v4 b)
{
    int i, bits = 0;
    for (i = 0; i < 4; ++i) bits |= (a.f[i] <= b.f[i]) << i;
    return bits;
}
static inline int hairobb__v4_lt_bits(hairobb__v4 a, hairobb__v4 b)
{
    int i, bits = 0;
    for (i = 0; i < 4; ++i) bits |= (a.f[i] < b.f[i]) << i;
    return bits;
}
static inline void hairobb__v4_store(float *p, hairobb__v4 a) { memcpy(p, a.f, sizeof a.f); }
static inline hairobb__v4 hairobb__v4_abs(hairobb__v4 a)
{
    hairobb__v4 r;
    int i;
    for (i = 0; i < 4; ++i) r.f[i] = fabsf(a.f[i]);
    return r;
}
static inline hairobb__v4 hairobb__v4_sqrt(hairobb__v4 a)
{
    hairobb__v4 r;
    int i;
    for (i = 0; i < 4; ++i) r.f[i] = sqrtf(a.f[i]);
    return r;
}
static inline hairobb__v4 hairobb__v4_pairs(hairobb__v4 a, hairobb__v4 b, int k)
{
    hairobb__v4 r;
    r.f[0] = a.f[k]; r.f[1] = a.f[k + 1]; r.f[2] = b.f[k]; r.f[3] = b.f[k + 1];
    return r;
}
static inline hairobb__v4 hairobb__v4_next(hairobb__v4 a, hairobb__v4 b)
{
    hairobb__v4 r;
    r.f[0] = a.f[1]; r.f[1] = a.f[2]; r.f[2] = a.f[3]; r.f[3] = b.f[0];
    return r;
}
static inline void hairobb__v4_transpose(hairobb__v4 *a, hairobb__v4 *b, hairobb__v4 *c, hairobb__v4 *d)
{
    hairobb__v4 *rows[4];
    float m[4][4];
    int i, j;
    rows[0] = a; rows[1] = b; rows[2] = c; rows[3] = d;
    for (i = 0; i < 4; ++i) for (j = 0; j < 4; ++j) m[i][j] = rows[j]->f[i];
    for (i = 0; i < 4; ++i) memcpy(rows[i]->f, m[i], sizeof m[i]);
}
static inline float hairobb__v4_hmax(hairobb__v4 a)
{
    float t0 = a.f[0] > a.f[2] ? a.f[0] : a.f[2], t1 = a.f[1] > a.f[3] ? a.f[1] : a.f[3];
    return t0 > t1 ? t0 : t1;
}
#endif

#if HAIROBB__AVX
typedef __m256 hairobb__v8;
static inline hairobb__v8 hairobb__v8_load(const float *p) { return _mm256_loadu_ps(p); }
static inline hairobb__v8 hairobb__v8_set1(float x) { return _mm256_set1_ps(x); }
static inline hairobb__v8 hairobb__v8_add(hairobb__v8 a, hairobb__v8 b) { return _mm256_add_ps(a, b); }
static inline hairobb__v8 hairobb__v8_sub(hairobb__v8 a, hairobb__v8 b) { return _mm256_sub_ps(a, b); }
static inline hairobb__v8 hairobb__v8_mul(hairobb__v8 a, hairobb__v8 b) { return _mm256_mul_ps(a, b); }
static inline hairobb__v8 hairobb__v8_div(hairobb__v8 a, hairobb__v8 b) { return _mm256_div_ps(a, b); }
static inline hairobb__v8 hairobb__v8_min(hairobb__v8 a, hairobb__v8 b) { return _mm256_min_ps(a, b); }
static inline hairobb__v8 hairobb__v8_max(hairobb__v8 a, hairobb__v8 b) { return _mm256_max_ps(a, b); }
static inline int hairobb__v8_le_bits(hairobb__v8 a, hairobb__v8 b) { return _mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)); }
static inline int hairobb__v8_lt_bits(hairobb__v8 a, hairobb__v8 b) { return _mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LT_OQ)); }
static inline void hairobb__v8_store(float *p, hairobb__v8 a) { _mm256_storeu_ps(p, a); }
/* Each lane the one after it, lane 7 `last` (moves only). */
#if HAIROBB__AVX2
static inline hairobb__v8 hairobb__v8_next(hairobb__v8 a, float last)
{
    return _mm256_blend_ps(_mm256_permutevar8x32_ps(a, _mm256_setr_epi32(1, 2, 3, 4, 5, 6, 7, 7)), _mm256_set1_ps(last), 0x80);
}
#else
static inline hairobb__v8 hairobb__v8_next(hairobb__v8 a, float last)
{
    __m128 lo = _mm256_castps256_ps128(a), hi = _mm256_extractf128_ps(a, 1);
    return _mm256_insertf128_ps(_mm256_castps128_ps256(hairobb__v4_next(lo, hi)), hairobb__v4_next(hi, _mm_set1_ps(last)), 1);
}
#endif
#if HAIROBB__AVX2
/* lane i = a[index[i]], index in 0..3 */
static inline hairobb__v8 hairobb__v8_pick4(const float *a, const int *index)
{
    return _mm256_permutevar8x32_ps(_mm256_castps128_ps256(_mm_loadu_ps(a)), _mm256_loadu_si256((const __m256i *)(const void *)index));
}
#else
static inline hairobb__v8 hairobb__v8_pick4(const float *a, const int *index)
{
    return _mm256_setr_ps(a[index[0]], a[index[1]], a[index[2]], a[index[3]], a[index[4]], a[index[5]], a[index[6]], a[index[7]]);
}
#endif
#if HAIROBB__AVX2
static inline hairobb__v8 hairobb__v8_from_bytes(const signed char *q)
{
    return _mm256_cvtepi32_ps(_mm256_cvtepi8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)q)));
}
#else
static inline hairobb__v8 hairobb__v8_from_bytes(const signed char *q)
{
    return _mm256_set_m128(hairobb__v4_from_bytes(q + 4), hairobb__v4_from_bytes(q));
}
#endif
#else
/* Two 4-lane halves: SSE, or plain C through the 4-lane twin above. */
typedef struct hairobb__v8 { hairobb__v4 lo, hi; } hairobb__v8;
#define HAIROBB__V8_PAIR(op) hairobb__v8 r; r.lo = op(a.lo, b.lo); r.hi = op(a.hi, b.hi); return r
static inline hairobb__v8 hairobb__v8_load(const float *p) { hairobb__v8 r; r.lo = hairobb__v4_load(p); r.hi = hairobb__v4_load(p + 4); return r; }
static inline hairobb__v8 hairobb__v8_set1(float x) { hairobb__v8 r; r.lo = r.hi = hairobb__v4_set1(x); return r; }
static inline hairobb__v8 hairobb__v8_add(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_add); }
static inline hairobb__v8 hairobb__v8_sub(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_sub); }
static inline hairobb__v8 hairobb__v8_mul(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_mul); }
static inline hairobb__v8 hairobb__v8_div(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_div); }
static inline hairobb__v8 hairobb__v8_min(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_min); }
static inline hairobb__v8 hairobb__v8_max(hairobb__v8 a, hairobb__v8 b) { HAIROBB__V8_PAIR(hairobb__v4_max); }
#undef HAIROBB__V8_PAIR
static inline int hairobb__v8_le_bits(hairobb__v8 a, hairobb__v8 b) { return hairobb__v4_le_bits(a.lo, b.lo) | (hairobb__v4_le_bits(a.hi, b.hi) << 4); }
static inline int hairobb__v8_lt_bits(hairobb__v8 a, hairobb__v8 b) { return hairobb__v4_lt_bits(a.lo, b.lo) | (hairobb__v4_lt_bits(a.hi, b.hi) << 4); }
static inline void hairobb__v8_store(float *p, hairobb__v8 a) { hairobb__v4_store(p, a.lo); hairobb__v4_store(p + 4, a.hi); }
static inline hairobb__v8 hairobb__v8_next(hairobb__v8 a, float last)
{
    hairobb__v8 r;
    r.lo = hairobb__v4_next(a.lo, a.hi);
    r.hi = hairobb__v4_next(a.hi, hairobb__v4_set1(last));
    return r;
}
static inline hairobb__v8 hairobb__v8_pick4(const float *a, const int *index)
{
    float lanes[8];
    int i;
    for (i = 0; i < 8; ++i) lanes[i] = a[index[i]];
    return hairobb__v8_load(lanes);
}
#if HAIROBB__SSE && !HAIROBB__SSE41
/* SSE2: the 8 bytes in one load, each unpacked with itself, then each
   half as hairobb__v4_from_bytes */
static inline hairobb__v8 hairobb__v8_from_bytes(const signed char *q)
{
    hairobb__v8 r;
    __m128i bytes = _mm_loadl_epi64((const __m128i *)(const void *)q);
    bytes = _mm_unpacklo_epi8(bytes, bytes);
    r.lo = _mm_cvtepi32_ps(_mm_srai_epi32(_mm_unpacklo_epi16(bytes, bytes), 24));
    r.hi = _mm_cvtepi32_ps(_mm_srai_epi32(_mm_unpackhi_epi16(bytes, bytes), 24));
    return r;
}
#else
static inline hairobb__v8 hairobb__v8_from_bytes(const signed char *q)
{
    hairobb__v8 r;
    r.lo = hairobb__v4_from_bytes(q);
    r.hi = hairobb__v4_from_bytes(q + 4);
    return r;
}
#endif
#endif

/* Node-wide vectors: one lane per child. */
#if HAIROBB__W == 8
typedef hairobb__v8 hairobb__vn;
#define hairobb__vn_load hairobb__v8_load
#define hairobb__vn_set1 hairobb__v8_set1
#define hairobb__vn_add hairobb__v8_add
#define hairobb__vn_sub hairobb__v8_sub
#define hairobb__vn_mul hairobb__v8_mul
#define hairobb__vn_div hairobb__v8_div
#define hairobb__vn_min hairobb__v8_min
#define hairobb__vn_max hairobb__v8_max
#define hairobb__vn_le_bits hairobb__v8_le_bits
#define hairobb__vn_store hairobb__v8_store
#define hairobb__vn_from_bytes hairobb__v8_from_bytes
#elif HAIROBB__W == 4
typedef hairobb__v4 hairobb__vn;
#define hairobb__vn_load hairobb__v4_load
#define hairobb__vn_set1 hairobb__v4_set1
#define hairobb__vn_add hairobb__v4_add
#define hairobb__vn_sub hairobb__v4_sub
#define hairobb__vn_mul hairobb__v4_mul
#define hairobb__vn_div hairobb__v4_div
#define hairobb__vn_min hairobb__v4_min
#define hairobb__vn_max hairobb__v4_max
#define hairobb__vn_le_bits hairobb__v4_le_bits
#define hairobb__vn_store hairobb__v4_store
#define hairobb__vn_from_bytes hairobb__v4_from_bytes
#else
#error "HAIROBB_NODE_WIDTH must be 4 or 8"
#endif

/* ------------------------------------------------------------------------ */
/* >>segment_points  Segment points as traced                               */
/* ------------------------------------------------------------------------ */
/* The Bezier control points (x, y, z, r each) of a segment given in another
   basis: p its points (4, or 2 for Hermite and linear), t the Hermite
   derivatives. The same cubic, so the same curve and the same u; radii
   that overshoot below 0 (Catmull-Rom, Hermite) are clamped; B-spline and
   linear points are sums of the validated radii (>= 0) with positive
   weights, which round to >= 0 and need no clamp (a radius of -0 stays
   -0, equal to 0 in every comparison). One vector a
   point, each lane rounded as a coordinate's plain C was before (the
   build's trees and the copy's floats did not change): divisions stay
   divisions (by 6 or 3, not products with a rounded reciprocal), sums
   associate from the left. The clamp is a max with (-inf, -inf, -inf, 0):
   max(r, 0) on the radius as hairobb__maxf, and on a coordinate x the
   identity but for NaN, which no input makes (every caller's points were
   validated: finite, |x| <= HAIROBB__MAX_COORD); one instruction where a
   blend of lane 3 took two, three in SSE2. Inline, so the AVX2 kernels
   convert in AVX2 code. */
HAIROBB__INLINE void hairobb__to_bezier(hairobb_basis basis, const float *p, const float *t, float b[16])
{
    hairobb__v4 b0, b1, b2, b3;
    switch (basis) {
    case HAIROBB_BASIS_BSPLINE: {
        hairobb__v4 p0 = hairobb__v4_load(p), p1 = hairobb__v4_load(p + 4), p2 = hairobb__v4_load(p + 8);
        hairobb__v4 p3 = hairobb__v4_load(p + 12), two = hairobb__v4_set1(2.0f), four = hairobb__v4_set1(4.0f);
        hairobb__v4 third = hairobb__v4_set1(3.0f), sixth = hairobb__v4_set1(6.0f);
        b0 = hairobb__v4_div(hairobb__v4_add(hairobb__v4_add(p0, hairobb__v4_mul(four, p1)), p2), sixth);
        b1 = hairobb__v4_div(hairobb__v4_add(hairobb__v4_mul(two, p1), p2), third);
        b2 = hairobb__v4_div(hairobb__v4_add(p1, hairobb__v4_mul(two, p2)), third);
        b3 = hairobb__v4_div(hairobb__v4_add(hairobb__v4_add(p1, hairobb__v4_mul(four, p2)), p3), sixth);
        break;
    }
    case HAIROBB_BASIS_CATMULL_ROM: {
        hairobb__v4 p0 = hairobb__v4_load(p), p1 = hairobb__v4_load(p + 4), p2 = hairobb__v4_load(p + 8);
        hairobb__v4 p3 = hairobb__v4_load(p + 12), sixth = hairobb__v4_set1(6.0f);
        b0 = p1;
        b1 = hairobb__v4_add(p1, hairobb__v4_div(hairobb__v4_sub(p2, p0), sixth));
        b2 = hairobb__v4_sub(p2, hairobb__v4_div(hairobb__v4_sub(p3, p1), sixth));
        b3 = p2;
        break;
    }
    case HAIROBB_BASIS_HERMITE: {
        hairobb__v4 third = hairobb__v4_set1(3.0f);
        b0 = hairobb__v4_load(p);
        b3 = hairobb__v4_load(p + 4);
        b1 = hairobb__v4_add(b0, hairobb__v4_div(hairobb__v4_load(t), third));
        b2 = hairobb__v4_sub(b3, hairobb__v4_div(hairobb__v4_load(t + 4), third));
        break;
    }
    default: {   /* linear (Bezier input is used as it is) */
        hairobb__v4 two = hairobb__v4_set1(2.0f), third = hairobb__v4_set1(3.0f);
        b0 = hairobb__v4_load(p);
        b3 = hairobb__v4_load(p + 4);
        b1 = hairobb__v4_div(hairobb__v4_add(hairobb__v4_mul(two, b0), b3), third);
        b2 = hairobb__v4_div(hairobb__v4_add(b0, hairobb__v4_mul(two, b3)), third);
        break;
    }
    }
    if (basis == HAIROBB_BASIS_CATMULL_ROM || basis == HAIROBB_BASIS_HERMITE) {
        hairobb__v4 radius_floor = hairobb__v4_set3(-INFINITY, -INFINITY, -INFINITY);
        b0 = hairobb__v4_max(b0, radius_floor);
        b1 = hairobb__v4_max(b1, radius_floor);
        b2 = hairobb__v4_max(b2, radius_floor);
        b3 = hairobb__v4_max(b3, radius_floor);
    }
    hairobb__v4_store(b, b0);
    hairobb__v4_store(b + 4, b1);
    hairobb__v4_store(b + 8, b2);
    hairobb__v4_store(b + 12, b3);
}

/* A segment's points p in the BVH's basis (the caller's, or lerped) in
   Bezier form into scratch, at = their offset in the caller's arrays: each
   basis its own straight code, its basis a constant. Only Hermite reads
   tangents, which it has (and it never moves, so p is the caller's there).
   Bezier points never come here: in place, or lerped and returned. */
HAIROBB__INLINE void hairobb__converted_points(const hairobb_bvh *bvh, const float *p, size_t at, float scratch[16])
{
    switch (bvh->point_basis) {
    case HAIROBB_BASIS_CATMULL_ROM: hairobb__to_bezier(HAIROBB_BASIS_CATMULL_ROM, p, NULL, scratch); break;
    case HAIROBB_BASIS_BSPLINE: hairobb__to_bezier(HAIROBB_BASIS_BSPLINE, p, NULL, scratch); break;
    case HAIROBB_BASIS_HERMITE: hairobb__to_bezier(HAIROBB_BASIS_HERMITE, p, bvh->tangents + at, scratch); break;
    default: hairobb__to_bezier(HAIROBB_BASIS_LINEAR, p, NULL, scratch); break;
    }
}

/* Instrumented builds (tests/simd_variant.c) count the segments whose
   points are made on the fly, per pass of the kernels. */
#ifndef HAIROBB__POINTS_MADE
#define HAIROBB__POINTS_MADE() ((void)0)
#endif

/* Control points of a moving segment (its first point at vertex at / 4)
   at time (in [0, 1]), made into scratch: each float lerped between the
   two steps around it, then converted from another basis. Out of line
   (a cold path beside the leaf's), compiled with each pass of the
   kernels: AVX2 code calling SSE code pays a transition on every call
   (see tests/check_dispatch_calls.sh). No FMA in any pass, so they round
   alike. */
HAIROBB__NOINLINE static const float *hairobb__made_moving(const hairobb_bvh *bvh, size_t at, float time, float scratch[16]);
static const float *hairobb__made_moving(const hairobb_bvh *bvh, size_t at, float time, float scratch[16])
{
    float f = time * (float)(bvh->time_steps - 1), w, lerped[16];
    float *out = bvh->point_basis == HAIROBB_BASIS_BEZIER ? scratch : lerped;
    unsigned k = (unsigned)f;
    const float *a, *b;
    int j, points = (int)hairobb__basis_points(bvh->point_basis);
    hairobb__v4 wa, wb;
    if (k > bvh->time_steps - 2) k = bvh->time_steps - 2;
    w = f - (float)k;
    wa = hairobb__v4_set1(1.0f - w);
    wb = hairobb__v4_set1(w);
    a = bvh->time_vertices[k] + at;
    b = bvh->time_vertices[k + 1] + at;
    /* each point (x y z r) lerped: (1 - w) a + w b, as the plain twin rounds it */
    for (j = 0; j < points; ++j)
        hairobb__v4_store(out + 4 * j, hairobb__v4_add(hairobb__v4_mul(wa, hairobb__v4_load(a + 4 * j)),
                                                        hairobb__v4_mul(wb, hairobb__v4_load(b + 4 * j))));
    if (out == scratch) return scratch;
    /* another basis: its points lerped (linear: 2), then converted */
    hairobb__converted_points(bvh, lerped, at, scratch);
    return scratch;
}

/* The caller's segment whose first point is vertex at / 4 (no copy): in
   place, or made into scratch at time (a ray's; unused by static BVHs).
   A leaf finds at in leaf_offsets; reads by segment id, through
   hairobb__segment_points below. Static points of another basis are
   converted inline: out of line, or through a pointer to a function per
   basis, they cost more instructions and more time (callgrind and the
   bench's rounds). scratch: room for points made on the fly. */
HAIROBB__INLINE const float *hairobb__points_at(const hairobb_bvh *bvh, size_t at, float time, float scratch[16])
{
    if (bvh->points_in_place) return bvh->vertices + at;
    HAIROBB__POINTS_MADE();
    if (!bvh->time_steps) {
        hairobb__converted_points(bvh, bvh->vertices + at, at, scratch);
        return scratch;
    }
    return hairobb__made_moving(bvh, at, time, scratch);
}

/* The Bezier control points (x y z r, 4 each) of segment prim as traced
   at time: the copy's, or the caller's through its index. Every read by
   segment id (hit attributes, joints, secondary rays, refit, save's hash)
   comes here. */
HAIROBB__INLINE const float *hairobb__segment_points(const hairobb_bvh *bvh, uint32_t prim, float time, float scratch[16])
{
    /* likely: the default's copy, the other paths out of its way */
    if (HAIROBB__LIKELY(bvh->leaf_points != NULL)) return bvh->leaf_points + 16 * (size_t)bvh->point_refs[prim];
    return hairobb__points_at(bvh, 4 * (size_t)bvh->indices[prim], time, scratch);
}

/* Whether segments prim and prim + 1 (next) or prim - 1 are of one group:
   strands do not join across groups. */
HAIROBB__INLINE int hairobb__same_group(const hairobb_bvh *bvh, uint32_t prim, int next)
{
    uint32_t boundary;
    if (!bvh->group_first) return 1;
    boundary = bvh->group_first[hairobb__group_of(bvh, prim) + (next ? 1u : 0u)];
    return next ? prim + 1u < boundary : prim > boundary;
}

/* ------------------------------------------------------------------------ */
/* >>intersector  Ray / curve intersection: what ribbons and tubes share    */
/* ------------------------------------------------------------------------ */
/* The point of the ray at t, rounded (base), and that rounding (error: the
   ray's point is base + error), kept exactly where it could reach 2^-12 of
   reach (a radius; a ray starting 1e4 away from thin hair) and 0 where it
   cannot (most rays: the exact terms cost tens of instructions); reach 0
   keeps it always (tubes: two segments' bases meet exactly at a joint
   only so). Returns 0 where the terms overflow. */
HAIROBB__INLINE int hairobb__ray_point(const hairobb__ray_state *rs, float t, float reach, float base[4], float error[4])
{
    /* lanes x, y, z (and 0): the exact error of t dir by Dekker's product
       (each factor split into halves of 12 bits, whose products round not
       at all; no FMA, so every path rounds alike), and of org + t dir by
       Knuth's sum; round to nearest, barring overflow of 4097 t, 4097 dir */
    hairobb__v4 org = hairobb__v4_set3(rs->line.org[0], rs->line.org[1], rs->line.org[2]), dir = hairobb__v4_set3(rs->line.dir[0], rs->line.dir[1], rs->line.dir[2]);
    hairobb__v4 t4 = hairobb__v4_set1(t), along = hairobb__v4_mul(t4, dir), sum = hairobb__v4_add(org, along);
    float largest = hairobb__v4_hmax(hairobb__v4_add(hairobb__v4_abs(org), hairobb__v4_abs(along)));
    hairobb__v4_store(base, sum);
    if (!(largest * FLT_EPSILON > reach * (1.0f / 4096.0f))) {
        hairobb__v4_store(error, hairobb__v4_set1(0.0f));
        return largest < INFINITY;
    } else {
        hairobb__v4 split = hairobb__v4_set1(4097.0f), st = hairobb__v4_mul(split, t4), sd = hairobb__v4_mul(split, dir);
        hairobb__v4 t_high = hairobb__v4_sub(st, hairobb__v4_sub(st, t4)), t_low = hairobb__v4_sub(t4, t_high);
        hairobb__v4 d_high = hairobb__v4_sub(sd, hairobb__v4_sub(sd, dir)), d_low = hairobb__v4_sub(dir, d_high);
        hairobb__v4 product_error = hairobb__v4_add(
            hairobb__v4_add(hairobb__v4_add(hairobb__v4_sub(hairobb__v4_mul(t_high, d_high), along), hairobb__v4_mul(t_high, d_low)),
                            hairobb__v4_mul(t_low, d_high)),
            hairobb__v4_mul(t_low, d_low));
        hairobb__v4 along_part = hairobb__v4_sub(sum, org);
        hairobb__v4 sum_error = hairobb__v4_add(hairobb__v4_sub(org, hairobb__v4_sub(sum, along_part)), hairobb__v4_sub(along, along_part));
        float e[4];
        hairobb__v4_store(e, hairobb__v4_add(product_error, sum_error));
        memcpy(error, e, sizeof e);
        return fabsf(e[0]) + fabsf(e[1]) + fabsf(e[2]) < INFINITY;
    }
}

/* A segment's control points moved to origin (qx, qy, qz) and its radii
   r, lane i = control point i. */
HAIROBB__INLINE void hairobb__ray_points_v4(const float origin[3], const float *cp, hairobb__v4 *qx,
                                            hairobb__v4 *qy, hairobb__v4 *qz, hairobb__v4 *r)
{
    hairobb__v4 p0 = hairobb__v4_load(cp), p1 = hairobb__v4_load(cp + 4);
    hairobb__v4 p2 = hairobb__v4_load(cp + 8), p3 = hairobb__v4_load(cp + 12);
    hairobb__v4_transpose(&p0, &p1, &p2, &p3);
    *qx = hairobb__v4_sub(p0, hairobb__v4_set1(origin[0]));
    *qy = hairobb__v4_sub(p1, hairobb__v4_set1(origin[1]));
    *qz = hairobb__v4_sub(p2, hairobb__v4_set1(origin[2]));
    *r = p3;
}

/* Coordinate `row` of ray space (0: x, 1: y, 2: z) of the moved points. */
HAIROBB__INLINE hairobb__v4 hairobb__ray_row_v4(const hairobb__ray_state *rs, int row, hairobb__v4 qx, hairobb__v4 qy,
                                                hairobb__v4 qz)
{
    const float *f = rs->line.frame + 3 * row;
    return hairobb__v4_add(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1(f[0]), qx), hairobb__v4_mul(hairobb__v4_set1(f[1]), qy)),
                           hairobb__v4_mul(hairobb__v4_set1(f[2]), qz));
}

static void hairobb__to_power_form(const hairobb__ray_curve *c, hairobb__ray_poly *p)
{
    hairobb__v4 p0 = hairobb__v4_load(c->x), p1 = hairobb__v4_load(c->y), p2 = hairobb__v4_load(c->z);
    hairobb__v4 p3 = hairobb__v4_load(c->r), three = hairobb__v4_set1(3.0f), two = hairobb__v4_set1(2.0f), a2, a3;
    hairobb__v4_transpose(&p0, &p1, &p2, &p3);     /* rows: control points (x, y, z, r) */
    a2 = hairobb__v4_mul(three, hairobb__v4_add(hairobb__v4_sub(p2, hairobb__v4_mul(two, p1)), p0));
    a3 = hairobb__v4_sub(hairobb__v4_add(hairobb__v4_sub(p3, hairobb__v4_mul(three, p2)), hairobb__v4_mul(three, p1)), p0);
    hairobb__v4_store(p->a[0], p0);
    hairobb__v4_store(p->a[1], hairobb__v4_mul(three, hairobb__v4_sub(p1, p0)));
    hairobb__v4_store(p->a[2], a2);
    hairobb__v4_store(p->a[3], a3);
    hairobb__v4_store(p->d[0], hairobb__v4_mul(two, a2));
    hairobb__v4_store(p->d[1], hairobb__v4_mul(three, a3));
    hairobb__v4_store(p->d[2], hairobb__v4_mul(hairobb__v4_set1(6.0f), a3));
}

/* x, y, z, r at u (all lanes u) in one 4-wide Horner evaluation, and
   (where asked) their first two derivatives. */
HAIROBB__INLINE hairobb__v4 hairobb__horner(const hairobb__ray_poly *p, hairobb__v4 u, hairobb__v4 *d1, hairobb__v4 *d2)
{
    if (d1) *d1 = hairobb__v4_add(hairobb__v4_mul(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_load(p->d[1]), u), hairobb__v4_load(p->d[0])), u),
                                  hairobb__v4_load(p->a[1]));
    if (d2) *d2 = hairobb__v4_add(hairobb__v4_mul(hairobb__v4_load(p->d[2]), u), hairobb__v4_load(p->d[0]));
    return hairobb__v4_add(hairobb__v4_mul(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_add(hairobb__v4_mul(
        hairobb__v4_load(p->a[3]), u), hairobb__v4_load(p->a[2])), u), hairobb__v4_load(p->a[1])), u), hairobb__v4_load(p->a[0]));
}

/* n made a unit vector in place; 0 where it has no length (zero, or not
   finite). Where its squared length leaves float's normal range (a
   normal of 1e-20 and less, found where a ray runs along a ribbon's
   tangent or a tube is that thin), it is first divided by its largest
   component, so that sqrtf keeps its bits; elsewhere the plain n /
   |n|. */
HAIROBB__INLINE int hairobb__normalize3(float n[3])
{
    float d = hairobb__dot3(n, n), length;
    int k;
    if (!(d >= 7.88860905e-31f && d <= 1.26765060e30f)) {   /* 2^-100, 2^100 */
        float largest = hairobb__maxf(hairobb__maxf(fabsf(n[0]), fabsf(n[1])), fabsf(n[2]));
        if (!(largest > 0.0f) || !(largest < INFINITY)) return 0;
        for (k = 0; k < 3; ++k) n[k] /= largest;
        d = hairobb__dot3(n, n);
    }
    length = sqrtf(d);
    for (k = 0; k < 3; ++k) n[k] /= length;
    return 1;
}

/* hairobb__bezier's value and first derivative for 4 curves at once, one
   per lane, rounded as it rounds: rows p0..p3 hold the control points. */
HAIROBB__INLINE void hairobb__bezier_v4(hairobb__v4 p0, hairobb__v4 p1, hairobb__v4 p2, hairobb__v4 p3, float u,
                               hairobb__v4 *value, hairobb__v4 *d1)
{
    float s = 1.0f - u;
    hairobb__v4 e0 = hairobb__v4_sub(p1, p0), e1 = hairobb__v4_sub(p2, p1), e2 = hairobb__v4_sub(p3, p2);
    *d1 = hairobb__v4_mul(hairobb__v4_set1(3.0f),
                          hairobb__v4_add(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1(s * s), e0),
                                                          hairobb__v4_mul(hairobb__v4_set1(2.0f * u * s), e1)),
                                          hairobb__v4_mul(hairobb__v4_set1(u * u), e2)));
    *value = hairobb__v4_add(hairobb__v4_add(hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1(s * s * s), p0),
                                                             hairobb__v4_mul(hairobb__v4_set1(3.0f * u * s * s), p1)),
                                             hairobb__v4_mul(hairobb__v4_set1(3.0f * u * u * s), p2)),
                             hairobb__v4_mul(hairobb__v4_set1(u * u * u), p3));
}

/* ------------------------------------------------------------------------ */
/* >>hit  Hits: attributes, filters, the nearest hit so far                 */
/* ------------------------------------------------------------------------ */
/* A tube's hit attributes, in world space from the segment's points cp:
   the tangent dP/du; v, the ribbon's formula at the tube's point X (the
   signed offset of the ray from the centre line across the fibre, over r);
   and the outward unit normal, the gradient of |X - c(u(X))|^2 -
   r(u(X))^2 with its curvature term: R - r r' c' / (|c'|^2 - R.c''), R = X
   - c(u). */
static void hairobb__tube_hit_at(const hairobb__ray_state *rs, const float *cp, float u, float t, int cap, hairobb_hit *hit)
{
    float s = 1.0f - u, b[4], db[4], d2b[4], C[4], T[4], T2[4], r, dr;
    float R[3], n[3], cross[3], along, tperp2, denominator, scale;
    const float *unit_dir = rs->line.frame + 6;
    hairobb__v4 value, tangent, second;
    int i, k;
    b[0] = s * s * s; b[1] = 3.0f * u * s * s; b[2] = 3.0f * u * u * s; b[3] = u * u * u;
    db[0] = -3.0f * s * s; db[1] = 3.0f * s * s - 6.0f * u * s; db[2] = 6.0f * u * s - 3.0f * u * u; db[3] = 3.0f * u * u;
    d2b[0] = 6.0f * s; d2b[1] = 6.0f * u - 12.0f * s; d2b[2] = 6.0f * s - 12.0f * u; d2b[3] = 6.0f * u;
    /* the sums over control points in order, x, y, z and r in the lanes
       (a lane rounds as a scalar sum from 0 would) */
    value = tangent = second = hairobb__v4_set1(0.0f);   /* 0 + -0 is +0, as a scalar sum from 0 */
    for (i = 0; i < 4; ++i) {
        hairobb__v4 point = hairobb__v4_load(cp + 4 * i);
        value = hairobb__v4_add(value, hairobb__v4_mul(hairobb__v4_set1(b[i]), point));
        tangent = hairobb__v4_add(tangent, hairobb__v4_mul(hairobb__v4_set1(db[i]), point));
        second = hairobb__v4_add(second, hairobb__v4_mul(hairobb__v4_set1(d2b[i]), point));
    }
    hairobb__v4_store(C, value);
    hairobb__v4_store(T, tangent);
    hairobb__v4_store(T2, second);
    r = hairobb__maxf(C[3], 0.0f);
    dr = T[3];
    for (k = 0; k < 3; ++k) R[k] = rs->line.org[k] + t * rs->line.dir[k] - C[k];
    memcpy(hit->tangent, T, sizeof hit->tangent);
    denominator = hairobb__dot3(T, T) - hairobb__dot3(R, T2);
    scale = denominator != 0.0f ? r * dr / denominator : 0.0f;
    for (k = 0; k < 3; ++k) n[k] = cap ? (u > 0.5f ? T[k] : -T[k]) : R[k] - scale * T[k];   /* a cap: along the strand, out */
    if (!hairobb__normalize3(n))   /* degenerate: against the ray */
        for (k = 0; k < 3; ++k) n[k] = -unit_dir[k];
    for (k = 0; k < 3; ++k) hit->Ng[k] = n[k];
    along = hairobb__dot3(T, unit_dir);
    tperp2 = hairobb__dot3(T, T) - along * along;
    cross[0] = T[1] * R[2] - T[2] * R[1];
    cross[1] = T[2] * R[0] - T[0] * R[2];
    cross[2] = T[0] * R[1] - T[1] * R[0];
    hit->v = 0.0f;
    if (r > 0.0f && tperp2 > 0.0f) {
        hit->v = hairobb__dot3(cross, unit_dir) / (sqrtf(tperp2) * r);
        hit->v = hairobb__maxf(-1.0f, hairobb__minf(1.0f, hit->v));
    }
}

/* Hit attributes of the hit at u, t on segment prim, c in ray space:
   computed once for the final hit, and for each one a hit filter is shown. */
/* A hit's ids: its group and the segment's index in it (a scene maps
   instance_id after). */
HAIROBB__INLINE void hairobb__hit_ids(const hairobb_bvh *bvh, uint32_t prim, hairobb_hit *hit)
{
    uint32_t group = hairobb__group_of(bvh, prim);
    hit->group_id = group;
    hit->prim_id = bvh->group_first ? prim - bvh->group_first[group] : prim;
    hit->instance_id = HAIROBB_INVALID_ID;
}

static void hairobb__hit_at(const hairobb_bvh *bvh, const hairobb__ray_state *rs, uint32_t prim, const float *points,
                            const hairobb__ray_curve *c, float u, float t, int cap, hairobb_hit *hit)
{
    float scratch[16];
    const float *cp = points ? points : hairobb__segment_points(bvh, prim, rs->line.time, scratch);
    if (hairobb__is_tube(bvh, prim)) {
        hairobb__tube_hit_at(rs, cp, u, t, cap, hit);
        hit->t = t;
        hit->u = u;
        hairobb__hit_ids(bvh, prim, hit);
        return;
    }
    hairobb__v4 x4 = hairobb__v4_load(c->x), y4 = hairobb__v4_load(c->y), z4 = hairobb__v4_set1(0.0f), r4 = hairobb__v4_load(c->r);
    hairobb__v4 value, d1, tangent, neg_dir, n4;
    float at[4], tangent_at[4], tangent_xy[2], x, y, r, tlen2, along, n[4];
    const float *unit_dir = rs->line.frame + 6;
    hairobb__bezier_v4(hairobb__v4_load(cp), hairobb__v4_load(cp + 4), hairobb__v4_load(cp + 8), hairobb__v4_load(cp + 12),
                       u, &value, &tangent);
    hairobb__v4_store(tangent_at, tangent);
    memcpy(hit->tangent, tangent_at, sizeof hit->tangent);
    hairobb__v4_transpose(&x4, &y4, &z4, &r4);     /* rows: control points (x, y, 0, r): z is not needed */
    hairobb__bezier_v4(x4, y4, z4, r4, u, &value, &d1);
    hairobb__v4_store(at, value);
    hairobb__v4_store(tangent_at, d1);
    x = at[0]; y = at[1]; r = at[3];
    tangent_xy[0] = tangent_at[0]; tangent_xy[1] = tangent_at[1];
    tlen2 = tangent_xy[0] * tangent_xy[0] + tangent_xy[1] * tangent_xy[1];
    hit->v = 0.0f;
    if (r > 0.0f && tlen2 > 0.0f) {
        hit->v = (tangent_xy[1] * x - tangent_xy[0] * y) / (sqrtf(tlen2) * r);
        hit->v = hairobb__maxf(-1.0f, hairobb__minf(1.0f, hit->v));
    }
    /* the ribbon's normal: -dir without its component along the tangent
       (lanes x, y, z; lane 3 is not used) */
    along = hairobb__dot3(unit_dir, hit->tangent);
    tlen2 = hairobb__dot3(hit->tangent, hit->tangent);
    neg_dir = hairobb__v4_set3(-unit_dir[0], -unit_dir[1], -unit_dir[2]);
    n4 = hairobb__v4_add(neg_dir, tlen2 > 0.0f ? hairobb__v4_div(hairobb__v4_mul(hairobb__v4_set1(along), tangent), hairobb__v4_set1(tlen2))
                                               : hairobb__v4_set1(0.0f));
    hairobb__v4_store(n, n4);
    if (!hairobb__normalize3(n)) hairobb__v4_store(n, neg_dir);   /* the ray along the tangent: against the ray */
    memcpy(hit->Ng, n, sizeof hit->Ng);
    hit->t = t;
    hit->u = u;
    hairobb__hit_ids(bvh, prim, hit);
}

/* The segment is moved to ray space again: the intersector's copy is not
   at hand in hairobb__accept. */
/* Whether the neighbour in index order begins (end 1) or ends (end 0)
   where this segment's end point is: a joint, smooth or a kink. */
static int hairobb__shares_end(const hairobb_bvh *bvh, uint32_t prim, int end, float time, const float *cp)
{
    float scratch[16];
    const float *q;
    if ((end ? (size_t)prim + 1 >= bvh->segment_count : prim == 0) || !hairobb__same_group(bvh, prim, end)) return 0;
    q = hairobb__segment_points(bvh, end ? prim + 1 : prim - 1, time, scratch) + 12 * (1 - end);
    cp += 12 * end;
    return cp[0] == q[0] && cp[1] == q[1] && cp[2] == q[2];
}

/* Whether the filters ignored this crossing already (HAIROBB__SHOWN): the
   same segment within 2^-10 of u, or at a joint the neighbour's matching
   end, at a t within r / 64 of the segment (plus t's rounding), on the
   same side of a tube (exit: 1 where the ray leaves it; ribbons 0). */
static int hairobb__ignored_before(const hairobb__ray_state *rs, uint32_t prim, float u, float t, int exit, const float *cp)
{
    const float near_end = 1.0f / 1024.0f;
    float close = hairobb__maxf(cp[3], cp[15]) * (1.0f / 64.0f) * rs->line.inv_dir_length + fabsf(t) * (1.0f / 65536.0f);
    int end = u <= near_end ? 0 : u >= 1.0f - near_end ? 1 : -1, list, i;
    for (list = 0; list < 2; ++list) {
        int kept = rs->shown.count[list] < HAIROBB__SHOWN ? rs->shown.count[list] : HAIROBB__SHOWN;
        for (i = 0; i < kept; ++i) {
            uint32_t other = rs->shown.prim[list][i];
            float other_u = rs->shown.u[list][i];
            if (!(fabsf(rs->shown.t[list][i] - t) <= close) || rs->shown.exit[list][i] != exit) continue;
            if (other == prim && fabsf(other_u - u) <= near_end) return 1;
            if (end == 1 && other == prim + 1 && other_u <= near_end && hairobb__shares_end(rs->call.bvh, prim, 1, rs->line.time, cp)) return 1;
            if (end == 0 && other + 1 == prim && other_u >= 1.0f - near_end && hairobb__shares_end(rs->call.bvh, prim, 0, rs->line.time, cp))
                return 1;
        }
    }
    return 0;
}

/* A hit in an instance's object space taken to world space (>>scene; a
   filter is shown world hits): the tangent by the map, the normal by its
   inverse transposed; t, u, v are the same. */
static void hairobb__hit_to_world(const hairobb__placed *placed, uint32_t id, hairobb_hit *hit)
{
    const float *m = placed->to_world, *inv = placed->to_object;
    float tangent[3], n[3];
    int i;
    for (i = 0; i < 3; ++i) {
        tangent[i] = m[4 * i] * hit->tangent[0] + m[4 * i + 1] * hit->tangent[1] + m[4 * i + 2] * hit->tangent[2];
        n[i] = inv[i] * hit->Ng[0] + inv[4 + i] * hit->Ng[1] + inv[8 + i] * hit->Ng[2];
    }
    if (hairobb__normalize3(n)) memcpy(hit->Ng, n, sizeof n);
    memcpy(hit->tangent, tangent, sizeof tangent);
    hit->instance_id = id;
}

/* Whether a filter drops the hit at u, t on segment prim (showing it the
   hit once): out of line, so that hairobb__accept stays small where no
   filter is set. cap: the hit is on a tube's end cap. */
HAIROBB__COLD static int hairobb__hit_filtered_out(hairobb__ray_state *rs, uint32_t prim, float u, float t, int cap)
{
    hairobb_hit hit;
    hairobb__ray_curve c;
    hairobb__v4 qx, qy, qz, r;
    float scratch[16];
    const float *cp = hairobb__segment_points(rs->call.bvh, prim, rs->line.time, scratch);
    int slot, list, exit;
    hairobb__ray_points_v4(rs->line.org, cp, &qx, &qy, &qz, &r);
    hairobb__v4_store(c.x, hairobb__ray_row_v4(rs, 0, qx, qy, qz));
    hairobb__v4_store(c.y, hairobb__ray_row_v4(rs, 1, qx, qy, qz));
    hairobb__v4_store(c.z, hairobb__ray_row_v4(rs, 2, qx, qy, qz));
    hairobb__v4_store(c.r, r);
    /* the hit first: a tube's side is its normal's (a ribbon's faces the ray) */
    hairobb__hit_at(rs->call.bvh, rs, prim, NULL, &c, u, t, cap, &hit);
    exit = hairobb__is_tube(rs->call.bvh, prim) && hairobb__dot3(hit.Ng, rs->line.dir) > 0.0f;
    if (hairobb__ignored_before(rs, prim, u, t, exit, cp)) return 1;
    if (rs->call.placed) hairobb__hit_to_world(rs->call.placed, rs->call.instance_id, &hit);
    if ((!rs->call.hit_filter || rs->call.hit_filter(rs->call.hit_filter_user, rs->call.ray, &hit)) &&
        (!rs->call.call_filter || rs->call.call_filter(rs->call.call_filter_user, rs->call.ray, &hit)))
        return 0;
    for (list = 0; list < 2; ++list) {
        if (list == 1 && u > 1.0f / 1024.0f && u < 1.0f - 1.0f / 1024.0f) break;
        slot = rs->shown.count[list]++ % HAIROBB__SHOWN;
        rs->shown.prim[list][slot] = prim;
        rs->shown.u[list][slot] = u;
        rs->shown.t[list][slot] = t;
        rs->shown.exit[list][slot] = exit;
    }
    return 1;
}

/* Records the hit at u, t on segment prim (cap: on a tube's end cap, as
   the filters are shown it) if t is in [tnear, tfar]: the nearest hit so
   far. Of two segments hit at the same t the smaller index wins, whatever
   the tree. A tube's caller records whether it took a cap (best.cap). */
HAIROBB__INLINE int hairobb__take(hairobb__ray_state *rs, uint32_t prim, float u, float t, int cap)
{
    if (!(t >= rs->line.tnear) || !(t <= rs->line.tfar)) return 0;
    if (t == rs->line.tfar && prim > rs->best.prim) return 0;
    /* a group the ray's mask excludes: its hits are not taken (tested here,
       where hits are few, a ray whose mask excludes no group pays nothing
       per segment) */
    if (rs->call.group_masked &&
        !(rs->call.bvh_groups->group_mask[hairobb__group_of(rs->call.bvh_groups, prim)] & rs->call.ray_mask))
        return 0;
    if (rs->call.filtering) {
        /* occluded1 takes one hit: the filter is shown none after it */
        if (rs->call.any_hit && rs->best.prim != HAIROBB_INVALID_ID) return 0;
        if (hairobb__hit_filtered_out(rs, prim, u, t, cap)) return 0;
    }
    rs->line.tfar = t;
    rs->best.prim = prim;
    rs->best.u = u;
    return 1;
}

/* hairobb__take of a hit on a ribbon or a tube's side: a function of its
   own, as the callers had it before caps (the compiler inlines it where
   it pays) */
static int hairobb__accept(hairobb__ray_state *rs, uint32_t prim, float u, float t) { return hairobb__take(rs, prim, u, t, 0); }

/* ------------------------------------------------------------------------ */
/* >>ribbon  Ribbons: the pieces, their roots, the polish                   */
/* ------------------------------------------------------------------------ */
/* f(u) = dot(P2, P2') vanishes where the ribbon faces the ray; f'(u) too. */
static float hairobb__ribbon_f(const hairobb__ray_poly *c, float u, float *derivative)
{
    hairobb__v4 d1, d2, value = hairobb__horner(c, hairobb__v4_set1(u), &d1, &d2);
    float products[4], squares[4], second[4];
    hairobb__v4_store(products, hairobb__v4_mul(value, d1));
    if (derivative) {
        hairobb__v4_store(squares, hairobb__v4_mul(d1, d1));
        hairobb__v4_store(second, hairobb__v4_mul(value, d2));
        *derivative = squares[0] + squares[1] + second[0] + second[1];
    }
    return products[0] + products[1];
}

/* What a ribbon's functions share about the segment tested: set once by
   hairobb__intersect_curve and passed down (nothing of it in the ray's
   state). poly is made only once a piece passes the chord cull. */
typedef struct hairobb__ribbon_segment {
    const hairobb_bvh *bvh;
    const hairobb__ray_curve *curve;   /* its control points in ray space */
    hairobb__ray_poly poly;     /* the same in power form */
    const float *points;        /* its world points (its roots' t are polished on them) */
    uint32_t prim;
} hairobb__ribbon_segment;

/* The depth of a ribbon's root at u on the segment of world points cp,
   taken again relative to the point of the ray at its first estimate t
   (that point's rounding kept exactly and taken off, as
   hairobb__intersect_segment does for tubes), after one Newton step on f
   there (*u moves where it stays inside the segment):
   relative to a far origin a root's t carried a few ulps of the distance,
   far more than r allows on thin hair. In world space: with P, T the
   point and tangent relative to the ray's point and d its unit direction,
   z = P.d, f = P.T - z T.d, f' ~ |T|^2 - (T.d)^2. At u = 0 or 1 (a joint)
   the end point's own depth. Every root is polished before it is
   compared (hairobb__try_hit), so a ray with tnear = tfar = a hit's t
   finds that hit again, and the order of the tree does not matter. */
static float hairobb__polished_t(const hairobb__ray_state *rs, const hairobb__ribbon_segment *seg, float *u, float t)
{
    const float *cp = seg->points, *unit_dir = rs->line.frame + 6;
    float reach = hairobb__maxf(hairobb__maxf(cp[3], cp[7]), hairobb__maxf(cp[11], cp[15]));
    float base[4], error[4], p[4], d[4], z, z1, f, f1, step, u_polished = *u, polished;
    hairobb__v4 shift, correction, p0, p1, p2, p3, value, tangent;
    /* where t's rounding (tens of ulps of the distance) could reach 1e-4 r:
       most camera rays, few secondary rays */
    if (!(fabsf(t) * rs->line.dir_length * (64.0f * FLT_EPSILON) > 1e-4f * reach)) return t;
    if (!hairobb__ray_point(rs, t, reach, base, error)) return t;
    shift = hairobb__v4_set3(base[0], base[1], base[2]);
    correction = hairobb__v4_set3(error[0], error[1], error[2]);
    p0 = hairobb__v4_sub(hairobb__v4_sub(hairobb__v4_load(cp), shift), correction);
    p1 = hairobb__v4_sub(hairobb__v4_sub(hairobb__v4_load(cp + 4), shift), correction);
    p2 = hairobb__v4_sub(hairobb__v4_sub(hairobb__v4_load(cp + 8), shift), correction);
    p3 = hairobb__v4_sub(hairobb__v4_sub(hairobb__v4_load(cp + 12), shift), correction);
    hairobb__bezier_v4(p0, p1, p2, p3, u_polished, &value, &tangent);
    hairobb__v4_store(p, value);
    hairobb__v4_store(d, tangent);
    z = hairobb__dot3(p, unit_dir);
    if (u_polished != 0.0f && u_polished != 1.0f) {
        z1 = hairobb__dot3(d, unit_dir);
        f = hairobb__dot3(p, d) - z * z1;
        f1 = hairobb__dot3(d, d) - z1 * z1;
        step = f1 > 0.0f ? f / f1 : 0.0f;
        /* a correction (within 2^-10 of u) that stays in the segment, where
           the tangent is more than 7 degrees off the ray (along it f' vanishes
           and the step means nothing) */
        if (f1 >= hairobb__dot3(d, d) * (1.0f / 64.0f) && fabsf(step) <= 1.0f / 1024.0f && u_polished - step >= 0.0f &&
            u_polished - step <= 1.0f) {
            u_polished -= step;
            z -= z1 * step;   /* the second-order term, z'' step^2 / 2, is far below t's rounding */
        }
    }
    polished = t + z * rs->line.inv_dir_length;
    /* within 2^-17 of t (the rounding it corrects is tens of ulps): the
       segment cull's slack (HAIROBB__Z_SLACK, 2^-16) still covers it */
    if (!(fabsf(polished - t) <= fabsf(t) * (1.0f / 131072.0f))) return t;
    *u = u_polished;
    return polished;
}

static int hairobb__try_hit(hairobb__ray_state *rs, const hairobb__ribbon_segment *seg, float u)
{
    float at[4], r, t;
    hairobb__v4_store(at, hairobb__horner(&seg->poly, hairobb__v4_set1(u), NULL, NULL));
    r = hairobb__maxf(at[3], 0.0f);
    if (!(at[0] * at[0] + at[1] * at[1] <= r * r)) return 0;   /* hairobb__accept's test, before the polish */
    t = hairobb__polished_t(rs, seg, &u, at[2] * rs->line.inv_dir_length);
    return hairobb__accept(rs, seg->prim, u, t);
}

/* Root of f in [lo, hi] where f changes sign: Newton steps, bisection when a
   step leaves the bracket. A Newton step of 1e-7 or less ends the search
   before the bracket test: u has converged, and a step that rounds onto the
   bracket end just set to u must not restart bisection from the far end. */
static float hairobb__solve_bracketed(const hairobb__ray_poly *c, float lo, float hi, float f_lo, float f_hi)
{
    float u = f_lo == f_hi ? 0.5f * (lo + hi) : lo + (hi - lo) * (f_lo / (f_lo - f_hi));
    int iteration;
    if (!(u >= lo && u <= hi)) u = 0.5f * (lo + hi);
    for (iteration = 0; iteration < 24; ++iteration) {
        float derivative, f = hairobb__ribbon_f(c, u, &derivative), next;
        if (f == 0.0f) break;
        if ((f < 0.0f) == (f_lo < 0.0f)) { lo = u; f_lo = f; } else { hi = u; }
        next = u - f / derivative;
        if (fabsf(next - u) <= 1e-7f) {
            if (next >= lo && next <= hi) u = next;
            break;
        }
        if (!(next > lo && next < hi)) next = 0.5f * (lo + hi);
        if (fabsf(next - u) <= 1e-7f) { u = next; break; }
        u = next;
    }
    return u;
}

/* Roots of f in [a, b] without a sign change across it: two can hide where
   f dips through zero; they are looked for around the extremum, where f'
   changes sign. */
static int hairobb__refine_dip(hairobb__ray_state *rs, const hairobb__ribbon_segment *seg, float a, float b, float fa, float fb,
                               float da, float db)
{
    const hairobb__ray_poly *c = &seg->poly;
    float lo = a, hi = b, middle, f_middle, d_middle;
    int found = 0, iteration;
    if ((da < 0.0f) == (db < 0.0f)) return 0;
    for (iteration = 0; iteration < 20; ++iteration) {
        middle = 0.5f * (lo + hi);
        hairobb__ribbon_f(c, middle, &d_middle);
        if ((d_middle < 0.0f) == (da < 0.0f)) lo = middle; else hi = middle;
    }
    middle = 0.5f * (lo + hi);
    f_middle = hairobb__ribbon_f(c, middle, NULL);
    if ((f_middle < 0.0f) == (fa < 0.0f) && f_middle != 0.0f) return 0;
    found |= hairobb__try_hit(rs, seg, hairobb__solve_bracketed(c, a, middle, fa, f_middle));
    found |= hairobb__try_hit(rs, seg, hairobb__solve_bracketed(c, middle, b, f_middle, fb));
    return found;
}

/* Whether the segment's first (end 0) or last (end 1) control point is where
   the segment before (after) it in index order ends (begins), the two
   tangents there parallel within 1e-3: a smooth joint of a strand stored in
   order, as every renderer's buffers and .hair files are. (At a kink the
   ribbons part by more than rounding, as the definition has them.) */
static int hairobb__joint_at(const hairobb_bvh *bvh, uint32_t prim, int end, float time)
{
    float scratch[2][16], a[3], b[3], cross[3];
    const float *p, *q;
    int k;
    if ((end ? (size_t)prim + 1 >= bvh->segment_count : prim == 0) || !hairobb__same_group(bvh, prim, end)) return 0;
    p = hairobb__segment_points(bvh, prim, time, scratch[0]) + 12 * end;
    q = hairobb__segment_points(bvh, end ? prim + 1 : prim - 1, time, scratch[1]) + 12 * (1 - end);
    if (!(p[0] == q[0] && p[1] == q[1] && p[2] == q[2])) return 0;
    /* both tangents pointing along the strand, away from the joint's first segment */
    for (k = 0; k < 3; ++k) {
        a[k] = end ? p[k] - p[k - 4] : p[k + 4] - p[k];
        b[k] = end ? q[k + 4] - q[k] : q[k] - q[k - 4];
    }
    cross[0] = a[1] * b[2] - a[2] * b[1];
    cross[1] = a[2] * b[0] - a[0] * b[2];
    cross[2] = a[0] * b[1] - a[1] * b[0];
    return hairobb__dot3(a, b) > 0.0f && hairobb__dot3(cross, cross) <= 1e-6f * hairobb__dot3(a, a) * hairobb__dot3(b, b);
}

/* A root of f within rounding of a segment's end has no reliable sign: at
   a strand's joint, each segment may compute its root just past its own end
   and the ray would pass between them. At a joint, the end is tried as a
   root where |f| there is within f's rounding: f = x x' + y y' with x, y,
   x', y' each off by about 16 ulps of the control points' distance from
   the ray origin. Free ends (tips) take only the part of that rounding that
   does not grow with P2' (a root at the end where P' = 0, as when control
   points repeat): their ribbon ends where it is defined to. The end's
   values come from its control points (end 0: points 0, 1; end 1: 3, 2). */
static int hairobb__try_end(hairobb__ray_state *rs, const hairobb__ribbon_segment *seg, int end)
{
    const hairobb__ray_curve *c = seg->curve;
    int at = 3 * end, next = 1 + end;
    float x = c->x[at], y = c->y[at], dx = 3.0f * (c->x[next] - x), dy = 3.0f * (c->y[next] - y), f = x * dx + y * dy;
    float distance = hairobb__maxf(hairobb__maxf(hairobb__maxf(fabsf(x), fabsf(y)), fabsf(c->z[at])),
                                   hairobb__maxf(hairobb__maxf(fabsf(c->x[next]), fabsf(c->y[next])), fabsf(c->z[next])));
    float slack = distance * (16.0f * FLT_EPSILON), at_tip = slack * (fabsf(x) + fabsf(y));
    if (!(fabsf(f) <= at_tip) &&
        !(fabsf(f) <= at_tip + slack * (fabsf(dx) + fabsf(dy)) && hairobb__joint_at(seg->bvh, seg->prim, end, rs->line.time)))
        return 0;
    return hairobb__try_hit(rs, seg, (float)end);
}

/* hairobb__ribbon_f and its derivative at 8 parameters at once, rounded as
   it rounds. */
static void hairobb__ribbon_f_v8(const hairobb__ray_poly *c, const float u_lanes[8], hairobb__v8 *f, hairobb__v8 *derivative)
{
    hairobb__v8 u = hairobb__v8_load(u_lanes), x, y, dx, dy, ddx, ddy;
#define HAIROBB__HORNER(k, value, d1, d2) \
    value = hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul( \
        hairobb__v8_set1(c->a[3][k]), u), hairobb__v8_set1(c->a[2][k])), u), hairobb__v8_set1(c->a[1][k])), u), \
        hairobb__v8_set1(c->a[0][k])); \
    d1 = hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul(hairobb__v8_set1(c->d[1][k]), u), \
        hairobb__v8_set1(c->d[0][k])), u), hairobb__v8_set1(c->a[1][k])); \
    d2 = hairobb__v8_add(hairobb__v8_mul(hairobb__v8_set1(c->d[2][k]), u), hairobb__v8_set1(c->d[0][k]))
    HAIROBB__HORNER(0, x, dx, ddx);
    HAIROBB__HORNER(1, y, dy, ddy);
#undef HAIROBB__HORNER
    *derivative = hairobb__v8_add(hairobb__v8_add(hairobb__v8_add(hairobb__v8_mul(dx, dx), hairobb__v8_mul(dy, dy)),
                                                  hairobb__v8_mul(x, ddx)), hairobb__v8_mul(y, ddy));
    *f = hairobb__v8_add(hairobb__v8_mul(x, dx), hairobb__v8_mul(y, dy));
}

/* Roots of f in the piece [a, b], each tried as a hit: f and f' at its
   ends, middle and quarters evaluated at once; in each quarter a sign change
   brackets a root, without one a dip may hide two, and exact zeros are
   roots. One root a quarter at most is found; several in one piece (bends,
   cusps) each have theirs. Most quarters have none of these: lane masks
   find those that do, which are then taken in order. */
static int hairobb__refine_piece(hairobb__ray_state *rs, const hairobb__ribbon_segment *seg, float a, float b)
{
    const hairobb__ray_poly *c = &seg->poly;
    float u[8], f[8], d[8];
    hairobb__v8 f_lanes, d_lanes, zero = hairobb__v8_set1(0.0f);
    unsigned negative, positive, exact, cross, dip, bits;
    int found = 0;
    u[0] = a;
    u[4] = b;
    u[2] = 0.5f * (a + b);
    u[1] = 0.5f * (a + u[2]);
    u[3] = 0.5f * (u[2] + b);
    u[5] = u[6] = u[7] = b;
    hairobb__ribbon_f_v8(c, u, &f_lanes, &d_lanes);
    hairobb__v8_store(f, f_lanes);
    hairobb__v8_store(d, d_lanes);
    /* bit k: lane k; quarter k runs from lane k to k + 1: a strict sign
       change (an exact zero is tried as a root of its own), or a dip where
       f' changes sign without one */
    negative = (unsigned)hairobb__v8_lt_bits(f_lanes, zero);
    positive = (unsigned)hairobb__v8_lt_bits(zero, f_lanes);
    exact = (unsigned)(hairobb__v8_le_bits(f_lanes, zero) & hairobb__v8_le_bits(zero, f_lanes)) & 31u;
    cross = ((negative & (positive >> 1)) | (positive & (negative >> 1))) & 15u;
    negative = (unsigned)hairobb__v8_lt_bits(d_lanes, zero);
    dip = (negative ^ (negative >> 1)) & ~cross & 15u;
    bits = exact | cross | dip;
    while (bits) {
        int k = hairobb__lowest_bit(bits);
        bits &= bits - 1;
        if (exact >> k & 1u) found |= hairobb__try_hit(rs, seg, u[k]);
        if (cross >> k & 1u)
            found |= hairobb__try_hit(rs, seg, hairobb__solve_bracketed(c, u[k], u[k + 1], f[k], f[k + 1]));
        else if (dip >> k & 1u)
            found |= hairobb__refine_dip(rs, seg, u[k], u[k + 1], f[k], f[k + 1], d[k], d[k + 1]);
    }
    return found;
}

/* The linear piece alone (HAIROBB_PRECISION_PIECES): hit where the closest
   point of the chord to the ray axis lies within the interpolated radius. */
static int hairobb__piece_hit(hairobb__ray_state *rs, const hairobb__ray_curve *c, uint32_t prim,
                              float a, float b, float s)
{
    float xa = hairobb__bezier(c->x, a, NULL, NULL), xb = hairobb__bezier(c->x, b, NULL, NULL);
    float ya = hairobb__bezier(c->y, a, NULL, NULL), yb = hairobb__bezier(c->y, b, NULL, NULL);
    float za = hairobb__bezier(c->z, a, NULL, NULL), zb = hairobb__bezier(c->z, b, NULL, NULL);
    float ra = hairobb__bezier(c->r, a, NULL, NULL), rb = hairobb__bezier(c->r, b, NULL, NULL);
    float x = xa + s * (xb - xa), y = ya + s * (yb - ya), r = ra + s * (rb - ra);
    if (!(x * x + y * y <= r * r)) return 0;   /* the piece's point covers the ray axis */
    return hairobb__accept(rs, prim, a + s * (b - a), (za + s * (zb - za)) * rs->line.inv_dir_length);
}

/* The pieces stage of one segment that survived the cull, c in ray space. */
/* A piece of parameter length h strays from its chord by at most
   h^2/8 max|P''| and |P''| <= 6 max|second difference|: widening the chord
   test by that (and the same for r), plus rounding of the evaluated points,
   misses no root of the ribbon. */
static float hairobb__chord_pad(const hairobb__ray_curve *c, int pieces, float magnitude)
{
    /* both second differences of x and y in one vector (ddx0, ddx1, ddy0,
       ddy1), of r in lanes 0, 1 of another */
    hairobb__v4 x = hairobb__v4_load(c->x), y = hairobb__v4_load(c->y), r = hairobb__v4_load(c->r), two = hairobb__v4_set1(2.0f);
    hairobb__v4 dd = hairobb__v4_add(hairobb__v4_sub(hairobb__v4_pairs(x, y, 0), hairobb__v4_mul(two, hairobb__v4_pairs(x, y, 1))),
                                     hairobb__v4_pairs(x, y, 2));
    hairobb__v4 dd_r = hairobb__v4_add(hairobb__v4_sub(hairobb__v4_pairs(r, r, 0), hairobb__v4_mul(two, hairobb__v4_pairs(r, r, 1))),
                                       hairobb__v4_pairs(r, r, 2));
    float bend[4], bend_r[4];
    dd = hairobb__v4_mul(dd, dd);
    hairobb__v4_store(bend, hairobb__v4_sqrt(hairobb__v4_add(dd, hairobb__v4_pairs(dd, dd, 2))));
    hairobb__v4_store(bend_r, hairobb__v4_abs(dd_r));
    return (hairobb__maxf(hairobb__maxf(0.0f, bend[0]), bend[1]) + hairobb__maxf(hairobb__maxf(0.0f, bend_r[0]), bend_r[1])) *
           (0.75f / (float)(pieces * pieces)) + magnitude * (8.0f * FLT_EPSILON);
}

/* x, y, r at one end of each of 8 pieces: the weights w[i] of control
   point i, lane = piece. */
HAIROBB__INLINE void hairobb__piece_ends(const float (*w)[8], const hairobb__ray_curve *c, hairobb__v8 *x, hairobb__v8 *y,
                                         hairobb__v8 *r)
{
    hairobb__v8 w0 = hairobb__v8_load(w[0]), w1 = hairobb__v8_load(w[1]), w2 = hairobb__v8_load(w[2]), w3 = hairobb__v8_load(w[3]);
#define HAIROBB__EVAL(v) hairobb__v8_add(hairobb__v8_add(hairobb__v8_add(hairobb__v8_mul(w0, hairobb__v8_set1(v[0])), \
        hairobb__v8_mul(w1, hairobb__v8_set1(v[1]))), hairobb__v8_mul(w2, hairobb__v8_set1(v[2]))), hairobb__v8_mul(w3, hairobb__v8_set1(v[3])))
    *x = HAIROBB__EVAL(c->x);
    *y = HAIROBB__EVAL(c->y);
    *r = HAIROBB__EVAL(c->r);
#undef HAIROBB__EVAL
}

/* magnitude: the largest |x|, |y| of the control points; cp: their world points */
static int hairobb__intersect_curve(const hairobb_bvh *bvh, hairobb__ray_state *rs, const hairobb__ray_curve *c,
                                    float magnitude, uint32_t prim, const float *cp, int any_hit)
{
    hairobb__ribbon_segment seg;
    int have_poly = 0, chunk, found = 0;
    float pad = bvh->precision == HAIROBB_PRECISION_PIECES ? 0.0f : hairobb__chord_pad(c, bvh->pieces, magnitude);

    for (chunk = 0; chunk < bvh->piece_chunks; ++chunk) {
        const float (*w)[4][8] = bvh->piece_weights[chunk];
        hairobb__v8 end_x[2], end_y[2], end_r[2];
        hairobb__v8 dx, dy, len2, s, px, py, reach;
        unsigned bits, inside;
        float s_lanes[8];
        hairobb__piece_ends(w[0], c, &end_x[0], &end_y[0], &end_r[0]);
        if (bvh->pieces == 8) {
            /* a piece ends where the next begins (the same weights), the
               last at control point 3 (weights 0, 0, 0, 1) */
            end_x[1] = hairobb__v8_next(end_x[0], c->x[3]);
            end_y[1] = hairobb__v8_next(end_y[0], c->y[3]);
            end_r[1] = hairobb__v8_next(end_r[0], c->r[3]);
        } else {
            hairobb__piece_ends(w[1], c, &end_x[1], &end_y[1], &end_r[1]);
        }
        /* closest point of each chord to the ray axis (Nakamaru and Ohno) */
        dx = hairobb__v8_sub(end_x[1], end_x[0]);
        dy = hairobb__v8_sub(end_y[1], end_y[0]);
        len2 = hairobb__v8_max(hairobb__v8_add(hairobb__v8_mul(dx, dx), hairobb__v8_mul(dy, dy)), hairobb__v8_set1(FLT_MIN));
        s = hairobb__v8_div(hairobb__v8_sub(hairobb__v8_set1(0.0f), hairobb__v8_add(hairobb__v8_mul(end_x[0], dx), hairobb__v8_mul(end_y[0], dy))), len2);
        /* a flat ribbon has no end caps: the pieces alone are hit only between
           their ends; the exact test clamps, to find every candidate piece */
        inside = (unsigned)(hairobb__v8_le_bits(hairobb__v8_set1(0.0f), s) & hairobb__v8_le_bits(s, hairobb__v8_set1(1.0f)));
        s = hairobb__v8_max(hairobb__v8_min(s, hairobb__v8_set1(1.0f)), hairobb__v8_set1(0.0f));
        px = hairobb__v8_add(end_x[0], hairobb__v8_mul(s, dx));
        py = hairobb__v8_add(end_y[0], hairobb__v8_mul(s, dy));
        if (bvh->precision == HAIROBB_PRECISION_PIECES)
            reach = hairobb__v8_add(end_r[0], hairobb__v8_mul(s, hairobb__v8_sub(end_r[1], end_r[0])));
        else
            reach = hairobb__v8_add(hairobb__v8_max(end_r[0], end_r[1]), hairobb__v8_set1(pad));
        bits = (unsigned)hairobb__v8_le_bits(hairobb__v8_add(hairobb__v8_mul(px, px), hairobb__v8_mul(py, py)),
                                             hairobb__v8_mul(reach, reach)) & bvh->chunk_valid[chunk];
        if (bvh->precision == HAIROBB_PRECISION_PIECES) {
            bits &= inside;
            if (bits) hairobb__v8_store(s_lanes, s);
        }
        while (bits) {
            int lane = hairobb__lowest_bit(bits), k = 8 * chunk + lane;
            float a = (float)k / (float)bvh->pieces, b = (float)(k + 1) / (float)bvh->pieces;
            bits &= bits - 1;
            if (bvh->precision == HAIROBB_PRECISION_PIECES) {
                found |= hairobb__piece_hit(rs, c, prim, a, b, s_lanes[lane]);
            } else {
                if (!have_poly) {
                    hairobb__to_power_form(c, &seg.poly);
                    seg.bvh = bvh;
                    seg.curve = c;
                    seg.points = cp;
                    seg.prim = prim;
                    have_poly = 1;
                }
                found |= hairobb__refine_piece(rs, &seg, a, b);
                if (k == 0) found |= hairobb__try_end(rs, &seg, 0);
                if (k == bvh->pieces - 1) found |= hairobb__try_end(rs, &seg, 1);
            }
            if (found && any_hit) return 1;
        }
    }
    return found;
}

/* ------------------------------------------------------------------------ */
/* >>tube  Tubes: inside intervals and both sheets' roots                   */
/* ------------------------------------------------------------------------ */
/* Round curves (HAIROBB_SHAPE_ROUND): the tube swept by a circle of radius
   r(u) about the centre line in the plane normal to its tangent. In ray
   space, with P2 = (x, y) and w = x x' + y y', that plane meets the ray at
   depth z + w / z', and the ray meets the circle where w^2 = z'^2 (r^2 -
   |P2|^2). Hits lie where the ray passes within r of the centre, q = |P2|^2
   - r^2 <= 0: the inside intervals of u. There, with S = sqrt(-q), the two
   sheets are the roots of
       g(u) = w + sheet z' S:   sheet +1, the entry, at depth z - S;
                                sheet -1, the exit,  at depth z + S.
   The inside intervals are found from q at up to HAIROBB__TUBE_SAMPLES + 1
   values of u (spaced 1/32 apart over the part of u where the hull of q's
   Bernstein coefficients reaches 0; 1/16 missed short inside intervals of
   very curvy segments), their ends refined by Newton steps on q kept in
   the bracket (hairobb__tube_edge); a minimum of q between two samples
   (q' = 2 (w - r r') changes sign there) is found too (regula falsi on
   q', hairobb__tube_low), so a ray that grazes the tube between samples is not lost. Each
   inside interval is sampled again at HAIROBB__TUBE_INSIDE_SAMPLES + 1
   values, and each sign change of g that can still give an accepted hit
   (hairobb__tube_root_unreachable; the exit sheet's after the entry
   sheet's) refined by Newton steps kept in the bracket, each converged
   step confirmed by a sign change just past it, since S' is infinite at
   the interval's ends (hairobb__tube_root). A long interval (a ray along
   a bent fibre) is sampled at 4x the outer spacing. Two roots of one
   sheet within one step of an inside interval can still be missed. At a
   smooth joint the shared end counts as a root within rounding
   (hairobb__tube_joint), so strands are watertight there. */
#define HAIROBB__TUBE_SAMPLES 32
#define HAIROBB__TUBE_INSIDE_SAMPLES 8
/* A tube's values at one u (hairobb__tube_at) */
typedef struct hairobb__tube_point {
    float w;                    /* x x' + y y' */
    float dz;                   /* z' */
    float z;
    float s;                    /* S = sqrt(-q) inside, else 0 */
    float q;                    /* |P2|^2 - r^2 */
    float half_slope;           /* q' / 2 = w - r r' */
    float tangent2;             /* |P'|^2 */
    float scale;                /* |P2|^2 + r^2: q's magnitude */
} hairobb__tube_point;

/* From Horner's value v and derivative d (lanes x, y, z, r): q = |P2|^2 -
   r^2, with *r = max(r, 0) and *w = x x' + y y', rounded as every scalar
   tube evaluation rounds them (the 8-lane ones repeat these steps). */
HAIROBB__INLINE float hairobb__tube_q(const float v[4], const float d[4], float *r, float *w)
{
    *r = hairobb__maxf(v[3], 0.0f);
    *w = v[0] * d[0] + v[1] * d[1];
    return v[0] * v[0] + v[1] * v[1] - *r * *r;
}

/* The tube's values at u */
static void hairobb__tube_at(const hairobb__ray_poly *p, float u, hairobb__tube_point *out)
{
    hairobb__v4 d1, value = hairobb__horner(p, hairobb__v4_set1(u), &d1, NULL);
    float v[4], d[4], r, q;
    hairobb__v4_store(v, value);
    hairobb__v4_store(d, d1);
    q = hairobb__tube_q(v, d, &r, &out->w);
    out->dz = d[2];
    out->z = v[2];
    out->s = q < 0.0f ? sqrtf(-q) : 0.0f;
    out->q = q;
    out->half_slope = out->w - r * d[3];
    out->tangent2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    out->scale = q + 2.0f * r * r;
}

/* x, y, z or r (lane k of the power form) at 8 values of u, and (where
   asked) its derivative, rounded as hairobb__horner rounds each lane. */
HAIROBB__INLINE hairobb__v8 hairobb__horner_v8(const hairobb__ray_poly *p, int k, hairobb__v8 u, hairobb__v8 *d1)
{
    if (d1) *d1 = hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul(hairobb__v8_set1(p->d[1][k]), u),
                                                                  hairobb__v8_set1(p->d[0][k])), u), hairobb__v8_set1(p->a[1][k]));
    return hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul(hairobb__v8_add(hairobb__v8_mul(
        hairobb__v8_set1(p->a[3][k]), u), hairobb__v8_set1(p->a[2][k])), u), hairobb__v8_set1(p->a[1][k])), u),
        hairobb__v8_set1(p->a[0][k]));
}

/* q and q' / 2 (hairobb__tube_at's out[4], out[5]) at 8 values of u at
   once, each lane rounded as hairobb__tube_at rounds (the same products
   and sums in the same order), so the samples agree on every path. */
static void hairobb__tube_q_v8(const hairobb__ray_poly *p, const float u_lanes[8], float q_out[8], float slope_out[8])
{
    hairobb__v8 u = hairobb__v8_load(u_lanes), x, y, r, dx, dy, dr, q, w;
    x = hairobb__horner_v8(p, 0, u, &dx);
    y = hairobb__horner_v8(p, 1, u, &dy);
    r = hairobb__horner_v8(p, 3, u, &dr);
    r = hairobb__v8_max(r, hairobb__v8_set1(0.0f));
    q = hairobb__v8_sub(hairobb__v8_add(hairobb__v8_mul(x, x), hairobb__v8_mul(y, y)), hairobb__v8_mul(r, r));
    w = hairobb__v8_add(hairobb__v8_mul(x, dx), hairobb__v8_mul(y, dy));
    hairobb__v8_store(q_out, q);
    hairobb__v8_store(slope_out, hairobb__v8_sub(w, hairobb__v8_mul(r, dr)));
}

/* Both sheets' g (hairobb__tube_g, sheet +1 and -1) at 8 values of u at
   once, rounded as the scalar path rounds: w + z' S and w - z' S, S =
   sqrt(-q) inside and 0 elsewhere (sqrt is exact-rounded on every path);
   and the centre line's depth z. */
static void hairobb__tube_g_v8(const hairobb__ray_poly *p, const float u_lanes[8], float entry_out[8], float exit_out[8],
                               float depth_out[8])
{
    hairobb__v8 u = hairobb__v8_load(u_lanes), x, y, r, dx, dy, dz, q, w, along_s;
    float lanes[8];
    x = hairobb__horner_v8(p, 0, u, &dx);
    y = hairobb__horner_v8(p, 1, u, &dy);
    hairobb__v8_store(depth_out, hairobb__horner_v8(p, 2, u, &dz));
    r = hairobb__horner_v8(p, 3, u, NULL);
    r = hairobb__v8_max(r, hairobb__v8_set1(0.0f));
    q = hairobb__v8_sub(hairobb__v8_add(hairobb__v8_mul(x, x), hairobb__v8_mul(y, y)), hairobb__v8_mul(r, r));
    w = hairobb__v8_add(hairobb__v8_mul(x, dx), hairobb__v8_mul(y, dy));
    /* -q where q < 0, else 0 (max takes its second operand for NaN and ties) */
    hairobb__v8_store(lanes, hairobb__v8_max(hairobb__v8_sub(hairobb__v8_set1(0.0f), q), hairobb__v8_set1(0.0f)));
    hairobb__v4_store(lanes, hairobb__v4_sqrt(hairobb__v4_load(lanes)));
    hairobb__v4_store(lanes + 4, hairobb__v4_sqrt(hairobb__v4_load(lanes + 4)));
    along_s = hairobb__v8_mul(dz, hairobb__v8_load(lanes));
    hairobb__v8_store(entry_out, hairobb__v8_add(w, along_s));
    hairobb__v8_store(exit_out, hairobb__v8_sub(w, along_s));
}

static float hairobb__tube_g(const hairobb__tube_point *at, float sheet) { return at->w + sheet * at->dz * at->s; }

/* A point in [lo, hi] where q' changes sign (from negative, slope_lo at
   lo, to positive): the minimum of q between two outer samples, to 2^-14
   of the step, by regula falsi with the Illinois rule (q'' is not at
   hand); an exact zero of q' where one is met. */
static float hairobb__tube_low(const hairobb__ray_poly *p, float lo, float hi, float slope_lo, float slope_hi)
{
    int iteration, side = 0;
    float tolerance = (hi - lo) * (1.0f / 16384.0f);
    for (iteration = 0; iteration < 20 && hi - lo > tolerance; ++iteration) {
        hairobb__tube_point at;
        float u = lo + (hi - lo) * (slope_lo / (slope_lo - slope_hi));
        if (!(u > lo && u < hi)) u = 0.5f * (lo + hi);
        if (u <= lo || u >= hi) break;
        hairobb__tube_at(p, u, &at);
        if (at.half_slope == 0.0f) return u;
        if ((at.half_slope < 0.0f) == (slope_lo < 0.0f)) {
            lo = u;
            slope_lo = at.half_slope;
            if (side == -1) slope_hi *= 0.5f;
            side = -1;
        } else {
            hi = u;
            slope_hi = at.half_slope;
            if (side == 1) slope_lo *= 0.5f;
            side = 1;
        }
    }
    return 0.5f * (lo + hi);
}

/* An inside interval's end: where q changes sign in [lo, hi] (q_lo at lo,
   q_hi at hi), to 2^-14 of the step, as the end of the last bracket where
   q >= 0 (outside, S = 0): there both sheets' g are w, so a root of
   either sheet just inside the interval's true end still shows as a sign
   change of g between the last sample and this end (a point inside by
   rounding gave g a z' S term that could hide it); an exact zero of q
   where one is met. Newton steps on q (q' / 2 = w - r r'), kept in the
   bracket (halving where a step leaves it); once a step is within a
   quarter of the tolerance, one point just past its end on the far side
   closes the bracket: fewer evaluations than regula falsi. */
static float hairobb__tube_edge(const hairobb__ray_poly *p, float lo, float hi, float q_lo, float q_hi)
{
    float tolerance = (hi - lo) * (1.0f / 16384.0f), u = lo + (hi - lo) * (q_lo / (q_lo - q_hi)), next;
    int iteration, lo_inside = q_lo < 0.0f;
    for (iteration = 0; iteration < 20 && hi - lo > tolerance; ++iteration) {
        float v[4], d[4], r, w, q, half_slope;
        hairobb__v4 d1, value;
        if (!(u > lo && u < hi)) u = 0.5f * (lo + hi);
        if (u <= lo || u >= hi) break;
        /* q and q' / 2 only (hairobb__tube_at's out[4], out[5]) */
        value = hairobb__horner(p, hairobb__v4_set1(u), &d1, NULL);
        hairobb__v4_store(v, value);
        hairobb__v4_store(d, d1);
        q = hairobb__tube_q(v, d, &r, &w);
        half_slope = w - r * d[3];
        if (q == 0.0f) return u;
        if ((q < 0.0f) == lo_inside) lo = u; else hi = u;
        next = half_slope != 0.0f ? u - q / (2.0f * half_slope) : u;
        if (fabsf(next - u) <= 0.25f * tolerance)
            /* converged: a point a quarter tolerance past the step's end, on
               the root's side of u (which end of the bracket u became) */
            next = u == lo ? hairobb__maxf(next, u) + 0.25f * tolerance : hairobb__minf(next, u) - 0.25f * tolerance;
        u = next;
    }
    return lo_inside ? hi : lo;
}

/* u at samples first .. first + 7 of [a, b] cut into `samples` steps:
   sample 0 is a and sample `samples` b exactly, and lanes past it are b.
   out has room for 16 floats: b goes into the lanes from sample `samples`
   on as one store of 8 (a loop of scalar stores cost more), which may
   write up to 7 floats past lane 7. */
HAIROBB__INLINE void hairobb__tube_sample_u(float a, float b, int samples, int first, float out[16])
{
    static const float lane_index[8] = {0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f};
    hairobb__v8 step = hairobb__v8_div(hairobb__v8_add(hairobb__v8_set1((float)first), hairobb__v8_load(lane_index)),
                                       hairobb__v8_set1((float)samples));
    hairobb__v8_store(out, hairobb__v8_add(hairobb__v8_set1(a), hairobb__v8_mul(hairobb__v8_set1(b - a), step)));
    if (samples - first < 8) hairobb__v8_store(out + (samples - first), hairobb__v8_set1(b));   /* first <= samples */
    if (first == 0) out[0] = a;
}

/* A sheet's g (as hairobb__tube_g rounds it) and its derivative at u:
   g' = w' + sheet (z'' S + z' S'), w' = |P2'|^2 + P2.P2'', S' = -(q'/2) / S. */
static float hairobb__tube_g_slope(const hairobb__ray_poly *p, float u, float sheet, float *slope)
{
    hairobb__v4 d1, d2, value = hairobb__horner(p, hairobb__v4_set1(u), &d1, &d2);
    float v[4], d[4], dd[4], r, q, root_s, w;
    hairobb__v4_store(v, value);
    hairobb__v4_store(d, d1);
    hairobb__v4_store(dd, d2);
    q = hairobb__tube_q(v, d, &r, &w);
    root_s = q < 0.0f ? sqrtf(-q) : 0.0f;
    *slope = d[0] * d[0] + d[1] * d[1] + v[0] * dd[0] + v[1] * dd[1] +
             sheet * (dd[2] * root_s - (root_s > 0.0f ? d[2] * (w - r * d[3]) / root_s : 0.0f));
    return w + sheet * d[2] * root_s;
}

/* The root of a sheet's g in [lo, hi], where it changes sign (g_lo at lo,
   g_hi at hi): Newton steps kept in the bracket (halving where a step
   leaves it). A step of 2^-23 or less has converged if g changes sign
   within 2^-23 past it (S' is infinite where the ray leaves the tube's
   reach, and there a step can be small far from the root): then that
   step's end; else halving goes on. At most 30 evaluations (fewer than
   regula falsi takes to the float spacing of u). */
static float hairobb__tube_root(const hairobb__ray_poly *p, float lo, float hi, float g_lo, float g_hi, float sheet)
{
    const float tolerance = 1.0f / 8388608.0f;
    float u = lo + (hi - lo) * (g_lo / (g_lo - g_hi)), g, slope, next, probe = -1.0f, estimate = u;
    int iteration, lo_negative = g_lo < 0.0f;
    for (iteration = 0; iteration < 30; ++iteration) {
        if (!(u > lo && u < hi)) u = 0.5f * (lo + hi);
        if (u <= lo || u >= hi) break;
        g = hairobb__tube_g_slope(p, u, sheet, &slope);
        if (g == 0.0f) return u;
        if ((g < 0.0f) == lo_negative) lo = u; else hi = u;
        if (u == probe) {
            if (hi - lo <= 3.0f * tolerance) return estimate;   /* the probe closed the bracket */
            u = 0.5f * (lo + hi);   /* it did not: the step was misled (S'), halve */
            probe = -1.0f;
            continue;
        }
        next = u - g / slope;
        if (!(next > lo && next < hi)) {
            next = 0.5f * (lo + hi);
        } else if (fabsf(next - u) <= tolerance) {
            /* past the step's end, on the root's side of u */
            estimate = next;
            probe = u == lo ? hairobb__maxf(next, u) + tolerance : hairobb__minf(next, u) - tolerance;
            if (!(probe > lo && probe < hi)) return next;   /* the bracket is already that narrow */
            next = probe;
        }
        u = next;
    }
    return u;
}

/* What a tube's functions share about the segment tested: set once by
   hairobb__intersect_tube and passed down (nothing of it in the ray's state). */
typedef struct hairobb__tube_segment {
    const hairobb_bvh *bvh;
    hairobb__ray_poly poly;     /* the segment in ray space, in power form */
    uint32_t prim;
    float t_base;               /* t of the point of the ray the points are relative to */
    float min_tangent2;         /* |P'|^2 at or below it: no circle (a tangent vanishing) */
    float reach[2];             /* bounds on |z'| and on r over the segment */
} hairobb__tube_segment;

/* Whether no root of a sheet between samples u0 and u1 (the centre line's
   depths z0, z1 there) can be accepted, so that refining it would be
   wasted (a ray's other sheet, or a segment behind its nearest hit so
   far). reach: a bound on |z'| over the segment (3 max |z[k+1] - z[k]| of
   its control points) and on r (their largest r). Between the samples z
   lies within (z0 + z1) / 2 +- reach[0] (u1 - u0) / 2; a root's depth z -
   sheet S is that, less S <= r on the entry sheet (+1), plus S on the exit
   sheet (-1). The slack, 2^-14 of the magnitudes, covers the roundings of
   z: hairobb__tube_hit's t is the same rounded expression of a depth at
   least this bound, and rounding is monotone, so the answer is exact. */
static int hairobb__tube_root_unreachable(const hairobb__ray_state *rs, const hairobb__tube_segment *seg, float u0, float u1,
                                          float z0, float z1, float sheet)
{
    const float *reach = seg->reach;
    float middle = 0.5f * (z0 + z1), spread = 0.5f * reach[0] * (u1 - u0);
    float slack = (fabsf(z0) + fabsf(z1) + reach[0] + reach[1]) * (1.0f / 16384.0f);
    float nearest = middle - spread - slack - (sheet > 0.0f ? reach[1] : 0.0f);
    float farthest = middle + spread + slack + (sheet < 0.0f ? reach[1] : 0.0f);
    return seg->t_base + nearest * rs->line.inv_dir_length > rs->line.tfar ||
           seg->t_base + farthest * rs->line.inv_dir_length < rs->line.tnear;
}

/* Records a sheet's hit at u if the ray passes within r of the centre there. */
static int hairobb__tube_hit(hairobb__ray_state *rs, const hairobb__tube_segment *seg, float u, float sheet)
{
    const hairobb__ray_poly *p = &seg->poly;
    hairobb__tube_point at;
    float t;
    hairobb__tube_at(p, u, &at);
    /* no circle where the tangent (nearly) vanishes: at a repeated end
       point the tube shrinks to one circle, a set of no area, and a root
       there is float noise */
    /* a root just inside an interval's end can round to q > 0: q within
       its rounding counts as inside (S = 0 there) */
    if (!(at.q <= at.scale * (8.0f * FLT_EPSILON)) || !(at.tangent2 > seg->min_tangent2)) return 0;
    t = seg->t_base + (at.z - sheet * at.s) * rs->line.inv_dir_length;
    if (rs->call.cull_back_faces || (rs->skip.active && t < rs->skip.t)) {
        /* whether the root faces the ray (an entry, +1) or away (-1), by
           the normal's component along it (ray space: R = (-x, -y, -sheet
           S), n = R - k c', k = r r' / (|c'|^2 - R.c''), as
           hairobb__tube_hit_at): with taper and curvature an entry sheet's
           root can face away from the ray where it runs nearly along the
           fibre, so culling and a secondary ray's skip go by it, not by
           the sheet */
        hairobb__v4 d1, d2, value = hairobb__horner(p, hairobb__v4_set1(u), &d1, &d2);
        float v[4], d[4], dd[4], denominator, k, facing;
        hairobb__v4_store(v, value);
        hairobb__v4_store(d, d1);
        hairobb__v4_store(dd, d2);
        denominator = at.tangent2 + v[0] * dd[0] + v[1] * dd[1] + sheet * at.s * dd[2];
        k = denominator != 0.0f ? hairobb__maxf(v[3], 0.0f) * d[3] / denominator : 0.0f;
        facing = -sheet * at.s - k * d[2] > 0.0f ? -1.0f : 1.0f;
        if (facing < 0.0f && rs->call.cull_back_faces) return 0;
        if (rs->skip.active && t < rs->skip.t && facing == rs->skip.sheet) return 0;
    }
    if (!hairobb__accept(rs, seg->prim, u, t)) return 0;
    rs->best.cap = 0;
    return 1;
}

/* An end cap (end_caps ON): the flat disk of radius r at end 0 or 1, normal
   to the tangent there, where that end is free (no smooth joint with the
   next segment in index order: a tip, or a kink). The ray meets its plane
   at depth z + w / z' (hairobb__intersect_tube's terms), at distance^2 q +
   r^2 + (w / z')^2 from the centre. A ray going along the outward normal
   (-P' at end 0, P' at end 1) leaves the fibre there: an exit (sheet -1). */
static int hairobb__tube_cap(hairobb__ray_state *rs, const hairobb__tube_segment *seg, const hairobb__tube_point *at, int end)
{
    float along = at->dz, offset, t, sheet;
    /* the ray in the cap's plane, or no plane (hairobb__tube_hit) */
    if (!(along != 0.0f) || !(at->tangent2 > seg->min_tangent2)) return 0;
    offset = at->w / along;
    if (!(at->q + offset * offset <= 0.0f)) return 0;
    sheet = (along > 0.0f) == (end == 0) ? 1.0f : -1.0f;
    if (sheet < 0.0f && rs->call.cull_back_faces) return 0;
    t = seg->t_base + (at->z + offset) * rs->line.inv_dir_length;
    if (rs->skip.active && sheet == rs->skip.sheet && t < rs->skip.t) return 0;
    if (!(t >= rs->line.tnear) || !(t <= rs->line.tfar) || hairobb__joint_at(seg->bvh, seg->prim, end, rs->line.time)) return 0;
    if (!hairobb__take(rs, seg->prim, (float)end, t, 1)) return 0;
    rs->best.cap = 1;
    return 1;
}

/* At a strand's smooth joint (hairobb__joint_at) a sheet's root within
   rounding of the shared end can fall just outside both segments, and the
   ray would pass between them: as the ribbon's hairobb__try_end does, the
   end itself is a root where g there is within its rounding (w and z' S
   off by tens of ulps of the point's depth and distance times |P'|). at:
   hairobb__tube_at at u = end. */
static int hairobb__tube_joint(hairobb__ray_state *rs, const hairobb__tube_segment *seg, const hairobb__tube_point *at, int end)
{
    float slack = (fabsf(at->z) + sqrtf(at->scale)) * sqrtf(at->tangent2) * (64.0f * FLT_EPSILON), sheet;
    int found = 0, joint = -1;
    for (sheet = 1.0f; sheet >= -1.0f; sheet -= 2.0f) {
        float g = hairobb__tube_g(at, sheet);
        if (g == 0.0f || !(fabsf(g) <= slack)) continue;   /* exact zeros are hairobb__tube_inside's */
        if (joint < 0) joint = hairobb__joint_at(seg->bvh, seg->prim, end, rs->line.time);
        if (joint) found |= hairobb__tube_hit(rs, seg, (float)end, sheet);
    }
    return found;
}

/* A sign change of one sheet's g between two samples: their u, g and
   depth z */
typedef struct hairobb__tube_change {
    float u0, u1, g0, g1, z0, z1;
} hairobb__tube_change;

/* The exit sheet's roots held back by hairobb__tube_inside, in u order. */
static int hairobb__tube_exits(hairobb__ray_state *rs, const hairobb__tube_segment *seg, hairobb__tube_change exits[8], int *count)
{
    int k, found = 0;
    for (k = 0; k < *count; ++k) {
        const hairobb__tube_change *e = &exits[k];
        if (!hairobb__tube_root_unreachable(rs, seg, e->u0, e->u1, e->z0, e->z1, -1.0f))
            found |= hairobb__tube_hit(rs, seg, hairobb__tube_root(&seg->poly, e->u0, e->u1, e->g0, e->g1, -1.0f), -1.0f);
    }
    *count = 0;
    return found;
}

/* Both sheets' roots in the inside interval [a, b]: g of both sheets at
   the samples, 8 at a time (hairobb__tube_g_v8), each sign change refined. */
static int hairobb__tube_inside(hairobb__ray_state *rs, const hairobb__tube_segment *seg, float a, float b, int any_hit)
{
    const hairobb__ray_poly *p = &seg->poly;
    hairobb__tube_point end;
    float u_lanes[16], g_lanes[2][8], z_lanes[8], g_previous[2], u_previous = a, z_previous = 0.0f;
    /* the exit sheet's sign changes, refined after the entry sheet's (a
       nearest hit) unless hairobb__tube_root_unreachable then rules them
       out */
    hairobb__tube_change exits[8];
    /* a long interval (a ray along a bent fibre, which can cross one sheet
       twice) at the outer samples' spacing at least */
    int k, first, lane, side, found = 0, exit_count = 0, samples = (int)((b - a) * (float)(4 * HAIROBB__TUBE_SAMPLES)) + 1;
    unsigned carry_negative[2] = {0u, 0u}, carry_exact[2] = {0u, 0u};
    if (samples < HAIROBB__TUBE_INSIDE_SAMPLES) samples = HAIROBB__TUBE_INSIDE_SAMPLES;
    if (a == 0.0f) {
        hairobb__tube_at(p, a, &end);
        found |= hairobb__tube_joint(rs, seg, &end, 0);
        if (found && any_hit) return 1;
    }
    /* lane 0 of the first group is u = a, then the samples k = 1 .. samples;
       the lanes where either sheet's g is 0 or changes sign from the lane
       before (bits of the masks; carry: lane 7 of the group before) are
       visited, in order, entry sheet first */
    for (first = 0; first <= samples; first += 8) {
        unsigned valid = first + 8 <= samples + 1 ? 0xffu : (1u << (samples + 1 - first)) - 1u, events = 0, zero[2], change[2];
        hairobb__tube_sample_u(a, b, samples, first, u_lanes);
        hairobb__tube_g_v8(p, u_lanes, g_lanes[0], g_lanes[1], z_lanes);
        for (side = 0; side < 2; ++side) {
            hairobb__v8 g = hairobb__v8_load(g_lanes[side]), zero_v = hairobb__v8_set1(0.0f);
            unsigned negative = (unsigned)hairobb__v8_lt_bits(g, zero_v);
            unsigned exact = (unsigned)(hairobb__v8_le_bits(g, zero_v) & hairobb__v8_le_bits(zero_v, g));
            unsigned negative_before = (negative << 1) | carry_negative[side], exact_before = (exact << 1) | carry_exact[side];
            /* as g0 < 0 != g1 < 0 with neither 0 (NaN counts as positive) */
            change[side] = (negative ^ negative_before) & ~exact & ~exact_before & valid;
            zero[side] = exact & valid;
            carry_negative[side] = negative >> 7 & 1u;
            carry_exact[side] = exact >> 7 & 1u;
            events |= change[side] | zero[side];
        }
        if (first == 0) {
            events = (events & ~1u) | ((zero[0] | zero[1]) & 1u) << 1;   /* u = a: a root of k = 1's (lane 0 only) */
            g_previous[0] = g_lanes[0][0];
            g_previous[1] = g_lanes[1][0];
            z_previous = z_lanes[0];
            u_previous = a;
        }
        while (events) {
            lane = hairobb__lowest_bit(events);
            events &= events - 1u;
            k = first + lane;
            if (lane > 0) {
                g_previous[0] = g_lanes[0][lane - 1];
                g_previous[1] = g_lanes[1][lane - 1];
                z_previous = z_lanes[lane - 1];
                u_previous = u_lanes[lane - 1];
            }
            for (side = 0; side < 2; ++side) {
                float sheet = side == 0 ? 1.0f : -1.0f, g0 = g_previous[side], g1 = g_lanes[side][lane], u = u_lanes[lane];
                if (k == 1 && g0 == 0.0f) found |= hairobb__tube_hit(rs, seg, a, sheet);
                if (zero[side] >> lane & 1u) {
                    found |= hairobb__tube_hit(rs, seg, u, sheet);
                } else if (change[side] >> lane & 1u) {
                    if (side == 1 && !any_hit) {
                        if (exit_count == 8) found |= hairobb__tube_exits(rs, seg, exits, &exit_count);
                        exits[exit_count].u0 = u_previous;
                        exits[exit_count].u1 = u;
                        exits[exit_count].g0 = g0;
                        exits[exit_count].g1 = g1;
                        exits[exit_count].z0 = z_previous;
                        exits[exit_count++].z1 = z_lanes[lane];
                    } else if (!hairobb__tube_root_unreachable(rs, seg, u_previous, u, z_previous, z_lanes[lane], sheet)) {
                        found |= hairobb__tube_hit(rs, seg, hairobb__tube_root(p, u_previous, u, g0, g1, sheet), sheet);
                    }
                }
                if (found && any_hit) return 1;
            }
        }
        /* lane 7 is the next group's lane before its lane 0 */
        g_previous[0] = g_lanes[0][7];
        g_previous[1] = g_lanes[1][7];
        z_previous = z_lanes[7];
        u_previous = u_lanes[7];
    }
    found |= hairobb__tube_exits(rs, seg, exits, &exit_count);
    if (b == 1.0f) {
        hairobb__tube_at(p, b, &end);
        found |= hairobb__tube_joint(rs, seg, &end, 1);
    }
    return found;
}

/* The Bernstein coefficients of a^2 (degree 6) for a cubic a in
   Bernstein form, coefficient k in lane k (lane 7: 0). Each lane is
   (A p q + B s t) C for its pair products, which with B = 0 and C = 1
   rounds as the product alone: c0 = a0 a0, c1 = a0 a1, c2 = (6 a0 a2 +
   9 a1 a1) / 15, c3 = (2 a0 a3 + 18 a1 a2) / 20, c4 = (6 a1 a3 + 9 a2
   a2) / 15, c5 = a2 a3, c6 = a3 a3. */
HAIROBB__INLINE hairobb__v8 hairobb__tube_square(const float a[4])
{
    static const int p[8] = {0, 0, 0, 0, 1, 2, 3, 0}, q[8] = {0, 1, 2, 3, 3, 3, 3, 0};
    static const int s[8] = {0, 0, 1, 1, 2, 0, 0, 0}, t[8] = {0, 0, 1, 2, 2, 0, 0, 0};
    static const float A[8] = {1.0f, 1.0f, 6.0f, 2.0f, 6.0f, 1.0f, 1.0f, 0.0f}, B[8] = {0.0f, 0.0f, 9.0f, 18.0f, 9.0f, 0.0f, 0.0f, 0.0f};
    static const float C[8] = {1.0f, 1.0f, 1.0f / 15.0f, 1.0f / 20.0f, 1.0f / 15.0f, 1.0f, 1.0f, 0.0f};
    hairobb__v8 first = hairobb__v8_mul(hairobb__v8_mul(hairobb__v8_load(A), hairobb__v8_pick4(a, p)), hairobb__v8_pick4(a, q));
    hairobb__v8 second = hairobb__v8_mul(hairobb__v8_mul(hairobb__v8_load(B), hairobb__v8_pick4(a, s)), hairobb__v8_pick4(a, t));
    return hairobb__v8_mul(hairobb__v8_add(first, second), hairobb__v8_load(C));
}

static int hairobb__intersect_tube(const hairobb_bvh *bvh, hairobb__ray_state *rs, const hairobb__ray_curve *c, const float *cp,
                                   uint32_t prim, float t_base, int any_hit)
{
    hairobb__tube_segment seg;
    hairobb__tube_point at_end;
    float start = -1.0f, bernstein[8], scale;
    float sample_u[HAIROBB__TUBE_SAMPLES + 16], sample_q[HAIROBB__TUBE_SAMPLES + 8], sample_slope[HAIROBB__TUBE_SAMPLES + 8];
    float min_tangent2 = 0.0f, margin, u_lo, u_hi;
    int k, samples, found = 0, first_below, last_below, first;
    unsigned nonpositive, carry_inside = 0, carry_negative = 0;
    /* q's Bernstein coefficients bound it: all of them clearly positive,
       the ray passes farther than r from the centre line everywhere (most
       segments that pass the ribbon's cull) */
    {   /* the largest |P2|^2 and r^2 of a control point (each >= 0: their max in any order) */
        hairobb__v4 x = hairobb__v4_load(c->x), y = hairobb__v4_load(c->y), r = hairobb__v4_load(c->r);
        scale = hairobb__v4_hmax(hairobb__v4_max(hairobb__v4_add(hairobb__v4_mul(x, x), hairobb__v4_mul(y, y)), hairobb__v4_mul(r, r)));
    }
    margin = scale * (64.0f * FLT_EPSILON);
    {
        hairobb__v8 b = hairobb__v8_add(hairobb__v8_add(hairobb__v8_set1(0.0f), hairobb__tube_square(c->x)), hairobb__tube_square(c->y));
        b = hairobb__v8_sub(hairobb__v8_add(b, hairobb__v8_mul(hairobb__v8_set1(-1.0f), hairobb__tube_square(c->r))), hairobb__v8_set1(margin));
        hairobb__v8_store(bernstein, b);
        nonpositive = (unsigned)hairobb__v8_le_bits(b, hairobb__v8_set1(0.0f)) & 0x7fu;
    }
    if (!nonpositive) return 0;
    /* the curve (u, q(u)) lies in the hull of the points (i/6, b_i): q <= 0
       only between the extreme u where that hull reaches down to 0 (the
       points at or below the margin, and where a line between two points
       on either side of it crosses it). Most segments that pass the cull
       are near the ray over a small part of u: the samples below take
       that part only, at the same spacing. A line from point k to j
       crosses between k/6 and j/6 (in float too: each step is monotone),
       so only lines from a point left of the first point at or below 0
       can move u_lo, and only lines to one right of the last can move u_hi. */
    first_below = hairobb__lowest_bit(nonpositive);
    last_below = hairobb__highest_bit(nonpositive);
    u_lo = (float)first_below * (1.0f / 6.0f);
    u_hi = (float)last_below * (1.0f / 6.0f);
    {
        /* each point j above 0 against every k at or below it at once
           (lane k), the crossings of the points k the mask names taken */
        static const float lane_index[8] = {0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f};
        hairobb__v8 b = hairobb__v8_load(bernstein), index = hairobb__v8_load(lane_index), sixth = hairobb__v8_set1(1.0f / 6.0f);
        float crossing[8];
        int j;
        for (j = 0; j < first_below; ++j) {   /* the lines from j (above 0) to each k */
            hairobb__v8 bj = hairobb__v8_set1(bernstein[j]), fj = hairobb__v8_set1((float)j);
            unsigned left = nonpositive;
            hairobb__v8_store(crossing, hairobb__v8_mul(hairobb__v8_add(fj, hairobb__v8_mul(hairobb__v8_sub(index, fj),
                                                                                              hairobb__v8_div(bj, hairobb__v8_sub(bj, b)))), sixth));
            for (; left; left &= left - 1u) u_lo = hairobb__minf(u_lo, crossing[hairobb__lowest_bit(left)]);
        }
        for (j = last_below + 1; j < 7; ++j) {   /* from each k to j (above 0) */
            hairobb__v8 bj = hairobb__v8_set1(bernstein[j]), fj = hairobb__v8_set1((float)j);
            unsigned left = nonpositive;
            hairobb__v8_store(crossing, hairobb__v8_mul(hairobb__v8_add(index, hairobb__v8_mul(hairobb__v8_sub(fj, index),
                                                                                                 hairobb__v8_div(b, hairobb__v8_sub(b, bj)))), sixth));
            for (; left; left &= left - 1u) u_hi = hairobb__maxf(u_hi, crossing[hairobb__lowest_bit(left)]);
        }
    }
    /* widened past the crossings' rounding */
    u_lo = u_lo <= 1.0f / 1024.0f ? 0.0f : u_lo - 1.0f / 1024.0f;
    u_hi = u_hi >= 1.0f - 1.0f / 1024.0f ? 1.0f : u_hi + 1.0f / 1024.0f;
    samples = (int)((u_hi - u_lo) * (float)HAIROBB__TUBE_SAMPLES) + 1;
    {
        /* the control polygon's legs, leg k in lane k (lane 3: 0) */
        hairobb__v4 x = hairobb__v4_load(c->x), y = hairobb__v4_load(c->y), z = hairobb__v4_load(c->z);
        hairobb__v4 dx = hairobb__v4_sub(hairobb__v4_next(x, hairobb__v4_set1(c->x[3])), x);
        hairobb__v4 dy = hairobb__v4_sub(hairobb__v4_next(y, hairobb__v4_set1(c->y[3])), y);
        hairobb__v4 dz = hairobb__v4_sub(hairobb__v4_next(z, hairobb__v4_set1(c->z[3])), z);
        /* |P'|^2 below 2^-24 of the control polygon's largest (3 dP)^2: a tangent vanishing */
        min_tangent2 = hairobb__v4_hmax(hairobb__v4_mul(hairobb__v4_set1(9.0f), hairobb__v4_add(hairobb__v4_add(
            hairobb__v4_mul(dx, dx), hairobb__v4_mul(dy, dy)), hairobb__v4_mul(dz, dz)))) * (1.0f / 16777216.0f);
        /* a bound on |z'| over the segment (hairobb__tube_root_unreachable) */
        seg.reach[0] = hairobb__v4_hmax(hairobb__v4_mul(hairobb__v4_set1(3.0f), hairobb__v4_abs(dz)));
    }
    {
        /* and below (16 eps M)^2, M the largest world coordinate: a basis
           converted to Bezier rounds each point by a few ulps of M, so a
           segment of equal points (zero length) keeps a tangent of
           rounding noise, a disk in a random plane */
        hairobb__v4 lo = hairobb__v4_max(hairobb__v4_abs(hairobb__v4_load(cp)), hairobb__v4_abs(hairobb__v4_load(cp + 4)));
        hairobb__v4 hi = hairobb__v4_max(hairobb__v4_abs(hairobb__v4_load(cp + 8)), hairobb__v4_abs(hairobb__v4_load(cp + 12)));
        float largest[4], noise;
        hairobb__v4_store(largest, hairobb__v4_max(lo, hi));   /* x, y, z: not the radius, which rounds on its own */
        noise = hairobb__maxf(hairobb__maxf(largest[0], largest[1]), largest[2]) * (16.0f * FLT_EPSILON);
        min_tangent2 = hairobb__maxf(min_tangent2, noise * noise);
    }
    /* and a bound on r (hairobb__tube_root_unreachable) */
    seg.reach[1] = hairobb__maxf(hairobb__v4_hmax(hairobb__v4_load(c->r)), 0.0f);
    hairobb__to_power_form(c, &seg.poly);
    seg.bvh = bvh;
    seg.prim = prim;
    seg.t_base = t_base;
    seg.min_tangent2 = min_tangent2;
    /* q and q' at every sample first, 8 at a time (at most 33 + 1; a last
       partial group's spare lanes at u_hi) */
    for (first = 0; first <= samples; first += 8) {
        hairobb__tube_sample_u(u_lo, u_hi, samples, first, sample_u + first);
        hairobb__tube_q_v8(&seg.poly, sample_u + first, sample_q + first, sample_slope + first);
    }
    if (bvh->end_caps && u_lo == 0.0f && sample_q[0] <= 0.0f) {
        hairobb__tube_at(&seg.poly, u_lo, &at_end);
        if ((found = hairobb__tube_cap(rs, &seg, &at_end, 0)) && any_hit) return 1;
    }
    if (sample_q[0] < 0.0f) start = u_lo;   /* inside at the open end (or by rounding at u_lo) */
    /* the samples k where q goes in (q < 0) or out, or where q' goes from
       negative to positive with both samples outside (bits of the masks;
       carry: lane 7 of the group before), visited in order */
    for (first = 0; first <= samples; first += 8) {
        hairobb__v8 zero = hairobb__v8_set1(0.0f), slope = hairobb__v8_load(sample_slope + first);
        unsigned valid = (first + 8 <= samples + 1 ? 0xffu : (1u << (samples + 1 - first)) - 1u) & (first == 0 ? ~1u : ~0u);
        unsigned inside = (unsigned)hairobb__v8_lt_bits(hairobb__v8_load(sample_q + first), zero);
        unsigned negative = (unsigned)hairobb__v8_lt_bits(slope, zero), positive = (unsigned)hairobb__v8_lt_bits(zero, slope);
        unsigned inside_before = (inside << 1) | carry_inside, negative_before = (negative << 1) | carry_negative;
        unsigned events = ((inside ^ inside_before) | (~inside & ~inside_before & negative_before & positive)) & valid;
        carry_inside = inside >> 7 & 1u;
        carry_negative = negative >> 7 & 1u;
        while (events) {
            float u, u_previous, q_previous, q;
            k = first + hairobb__lowest_bit(events);
            events &= events - 1u;
            u = sample_u[k];
            u_previous = sample_u[k - 1];
            q_previous = sample_q[k - 1];
            q = sample_q[k];
            if (start < 0.0f && q < 0.0f) {   /* into an inside interval */
                start = hairobb__tube_edge(&seg.poly, u_previous, u, q_previous, q);
            } else if (start >= 0.0f && !(q < 0.0f)) {   /* out of it */
                found |= hairobb__tube_inside(rs, &seg, start, hairobb__tube_edge(&seg.poly, u_previous, u, q_previous, q), any_hit);
                start = -1.0f;
            } else if (start < 0.0f && sample_slope[k - 1] < 0.0f && sample_slope[k] > 0.0f) {
                /* both outside, but q has a minimum between them: inside there? */
                float low = hairobb__tube_low(&seg.poly, u_previous, u, sample_slope[k - 1], sample_slope[k]);
                hairobb__tube_point at;
                hairobb__tube_at(&seg.poly, low, &at);
                if (at.q < 0.0f)
                    found |= hairobb__tube_inside(rs, &seg, hairobb__tube_edge(&seg.poly, u_previous, low, q_previous, at.q),
                                                  hairobb__tube_edge(&seg.poly, low, u, at.q, q), any_hit);
            }
            if (found && any_hit) return 1;
        }
    }
    if (start >= 0.0f) found |= hairobb__tube_inside(rs, &seg, start, u_hi, any_hit);   /* inside at the other open end */
    if (found && any_hit) return 1;
    if (bvh->end_caps && u_hi == 1.0f && sample_q[samples] <= 0.0f) {
        hairobb__tube_at(&seg.poly, u_hi, &at_end);
        found |= hairobb__tube_cap(rs, &seg, &at_end, 1);
    }
    return found;
}

/* ------------------------------------------------------------------------ */
/* >>segment  A segment's cull, and a leaf's segments                       */
/* ------------------------------------------------------------------------ */
/* One segment: moved into ray space and culled by its control polygon (the
   ribbon lies in its hull dilated by the largest radius), then the pieces.
   (Culling 4 segments at once with SIMD measured slower: leaves hold
   about one segment.) Inlined into the leaf loop: out of line, its
   frame's set-up and tear-down cost more than the call saves. */
HAIROBB__INLINE int hairobb__intersect_segment(const hairobb_bvh *bvh, hairobb__ray_state *rs, uint32_t prim,
                                               const float *cp, int any_hit)
{
    hairobb__ray_curve c;
    hairobb__v4 qx, qy, qz, x, y, z, r, reach, neg_reach;
    float max_r, magnitude;
    int inside, tube;
    HAIROBB__COUNT(segment);
    hairobb__ray_points_v4(rs->line.org, cp, &qx, &qy, &qz, &r);
    x = hairobb__ray_row_v4(rs, 0, qx, qy, qz);
    y = hairobb__ray_row_v4(rs, 1, qx, qy, qz);
    max_r = hairobb__v4_hmax(r);
    reach = hairobb__v4_set1(max_r);
    neg_reach = hairobb__v4_set1(-max_r);
    /* some control point on the near side of each of the four lines
       x, y = +-max_r: each 4-bit mask is nonzero, that is, has bit 4 set
       once 15 is added. Most segments a ray reaches pass beside it (about
       half of those tested on the bench's scenes): this test first, alone. */
    inside = (hairobb__v4_le_bits(x, reach) + 15) & (hairobb__v4_le_bits(neg_reach, x) + 15) &
             (hairobb__v4_le_bits(y, reach) + 15) & (hairobb__v4_le_bits(neg_reach, y) + 15) & 16;
    if (!inside) return 0;
    tube = hairobb__is_tube(bvh, prim);   /* asked only of the segments left */
    /* The same for the planes z = tnear, tfar (times |dir|), and for the two
       lines parallel to the chord P0 P3 at distance max_r, widened by the
       rounding of the curve's points as the exact test evaluates them:
       |n.P2(u)| <= |n| |P2(u)| <= |n| r(u) on the ribbon, and n.P2(u) lies
       between the extreme n.Pi. The planes are widened too, by more than
       the exact test's rounding of t (its power form, Horner's rule and the
       scale by 1/|dir|: tens of ulps of the largest |z|; HAIROBB__Z_SLACK
       is 2^-16): tfar shrinks in the order the traversal finds hits, and a
       segment whose hit the exact test accepts at t <= tfar must never be
       culled here, whatever that order (SIMD paths may visit nodes in
       another order than plain C). */
    z = hairobb__ray_row_v4(rs, 2, qx, qy, qz);
    hairobb__v4_store(c.x, x);
    hairobb__v4_store(c.y, y);
    {
        float nx = c.y[0] - c.y[3], ny = c.x[3] - c.x[0], limit;
        float slack = hairobb__v4_hmax(hairobb__v4_abs(z)) * HAIROBB__Z_SLACK;
        float z_near = rs->line.tnear * rs->line.dir_length, z_far = rs->line.tfar * rs->line.dir_length;
        hairobb__v4 d;
        if (tube) slack += max_r;   /* a tube's sheets lie within r of its centre line's depth */
        z_near -= fabsf(z_near) * (8.0f * FLT_EPSILON) + slack;
        z_far += fabsf(z_far) * (8.0f * FLT_EPSILON) + slack;
        magnitude = hairobb__v4_hmax(hairobb__v4_max(hairobb__v4_abs(x), hairobb__v4_abs(y)));
        limit = sqrtf(nx * nx + ny * ny) * (max_r + magnitude * (16.0f * FLT_EPSILON));
        d = hairobb__v4_add(hairobb__v4_mul(hairobb__v4_set1(nx), x), hairobb__v4_mul(hairobb__v4_set1(ny), y));
        inside = (hairobb__v4_le_bits(hairobb__v4_set1(z_near), z) + 15) &
                 (hairobb__v4_le_bits(z, hairobb__v4_set1(z_far)) + 15) &
                 (hairobb__v4_le_bits(d, hairobb__v4_set1(limit)) + 15) & (hairobb__v4_le_bits(hairobb__v4_set1(-limit), d) + 15) & 16;
        if (!inside) return 0;   /* both tests, one branch */
    }
    hairobb__v4_store(c.z, z);
    hairobb__v4_store(c.r, r);
    HAIROBB__COUNT(segment_passed);
    if (tube) {
        /* A tube's points again, relative to the point of the ray at the
           depth of the segment's ends (as Embree's round curves): relative
           to a far origin the depth and the offsets from the ray carried a
           few ulps of the distance, several times t's own rounding. That
           point is rounded (by far more than r where the ray starts at
           1e4): the rounding, kept exactly (hairobb__ray_point), is taken
           off the differences of the nearby points. */
        float base[4], error[4], t_base = 0.5f * (c.z[0] + c.z[3]) * rs->line.inv_dir_length;
        if (hairobb__ray_point(rs, t_base, 0.0f, base, error)) {   /* reach 0: always exact, so joints meet */
            hairobb__ray_points_v4(base, cp, &qx, &qy, &qz, &r);
            qx = hairobb__v4_sub(qx, hairobb__v4_set1(error[0]));
            qy = hairobb__v4_sub(qy, hairobb__v4_set1(error[1]));
            qz = hairobb__v4_sub(qz, hairobb__v4_set1(error[2]));
        } else {   /* the split overflowed (|dir| near FLT_MAX): as tested above */
            t_base = 0.0f;
        }
        hairobb__v4_store(c.x, hairobb__ray_row_v4(rs, 0, qx, qy, qz));
        hairobb__v4_store(c.y, hairobb__ray_row_v4(rs, 1, qx, qy, qz));
        hairobb__v4_store(c.z, hairobb__ray_row_v4(rs, 2, qx, qy, qz));
        if (!hairobb__intersect_tube(bvh, rs, &c, cp, prim, t_base, any_hit)) return 0;
    } else {
        if (!hairobb__intersect_curve(bvh, rs, &c, magnitude, prim, cp, any_hit)) return 0;
    }
    if (!any_hit) {   /* the nearest hit so far is on this segment */
        rs->best.curve = c;
        /* kept for the hit's attributes: no lookup by prim, which misses at scale */
        rs->best.points = bvh->leaf_points || bvh->points_in_place ? cp : NULL;
    }
    return 1;
}

/* The segment a secondary ray leaves, or one joined to its ends (in its
   own group). */
static int hairobb__skipped(const hairobb_bvh *bvh, const hairobb__ray_state *rs, uint32_t prim, const float *cp)
{
    return prim == rs->skip.prim ||
           (((cp[0] == rs->skip.last[0] && cp[1] == rs->skip.last[1] && cp[2] == rs->skip.last[2]) ||
             (cp[12] == rs->skip.first[0] && cp[13] == rs->skip.first[1] && cp[14] == rs->skip.first[2])) &&
            hairobb__group_of(bvh, prim) == hairobb__group_of(bvh, rs->skip.prim));
}

static int hairobb__intersect_leaf(const hairobb_bvh *bvh, hairobb__ray_state *rs, uint64_t ref, int any_hit)
{
    size_t first = (size_t)(ref >> 8), count = (size_t)((ref >> 4) & 15u), i;
    const float *copy = bvh->leaf_points ? bvh->leaf_points + 16 * first : NULL;
    int found = 0, hit;
    /* the leaf's later segments asked for while the first is tested: one
       line each in the copy */
    if (copy) for (i = 1; i < count; ++i) HAIROBB__PREFETCH(copy + 16 * i);
    for (i = 0; i < count; ++i) {
        uint32_t prim = bvh->leaf_prims[first + i];
        float scratch[16];
        /* no load waits for prim: the copy holds the leaf's points on its
           own lines, or leaf_offsets says where the caller's are */
        const float *cp = copy ? copy + 16 * i
                               : hairobb__points_at(bvh, 4 * (size_t)bvh->leaf_offsets[first + i], rs->line.time, scratch);
        if (HAIROBB__LEAF_VISIT(rs, prim)) continue;
        if (rs->skip.t > 0.0f && hairobb__skipped(bvh, rs, prim, cp)) {
            if (rs->skip.sheet != 0.0f) {
                rs->skip.active = 1;   /* a tube: one sheet, near the origin (hairobb__tube_hit) */
                hit = hairobb__intersect_segment(bvh, rs, prim, cp, any_hit);
                rs->skip.active = 0;
            } else {
                /* a ribbon: this segment alone is tested from skip_t on */
                float tnear = rs->line.tnear;
                rs->line.tnear = hairobb__maxf(tnear, rs->skip.t);
                hit = rs->line.tnear <= rs->line.tfar && hairobb__intersect_segment(bvh, rs, prim, cp, any_hit);
                rs->line.tnear = tnear;
            }
        } else {
            hit = hairobb__intersect_segment(bvh, rs, prim, cp, any_hit);
        }
        if (hit) {
            found = 1;
            if (any_hit) return 1;
        }
    }
    return found;
}

/* ------------------------------------------------------------------------ */
/* >>traversal  Traversal: node tests, nearest first                        */
/* ------------------------------------------------------------------------ */
HAIROBB__INLINE hairobb__vn hairobb__far_scale(hairobb__vn tfar)
{
    return hairobb__vn_mul(tfar, hairobb__vn_set1(HAIROBB__FAR_SCALE));
}

/* Slab test of a node's boxes in the slab ray's frame; planes points at
   lower[3][W], followed by upper[3][W] ([axis][child] arrays). */
HAIROBB__INLINE int hairobb__intersect_boxes(const float *planes, const hairobb__slab_ray *slab,
                                             const hairobb__ray_state *rs, float dist[HAIROBB__W])
{
    hairobb__vn tn = hairobb__vn_set1(rs->line.tnear), tf = hairobb__vn_set1(rs->line.tfar);
#define HAIROBB__SLAB_AXIS(k) do { \
        hairobb__vn o = hairobb__vn_set1(slab->org[k]), r = hairobb__vn_set1(slab->rdir[k]); \
        tn = hairobb__vn_max(hairobb__vn_mul(hairobb__vn_sub(hairobb__vn_load(planes + slab->near_plane[k]), o), r), tn); \
        tf = hairobb__vn_min(hairobb__vn_mul(hairobb__vn_sub(hairobb__vn_load(planes + slab->far_plane[k]), o), r), tf); \
    } while (0)
    HAIROBB__SLAB_AXIS(0);   /* written out, as in hairobb__intersect_compressed_obb_node */
    HAIROBB__SLAB_AXIS(1);
    HAIROBB__SLAB_AXIS(2);
#undef HAIROBB__SLAB_AXIS
    hairobb__vn_store(dist, tn);
    return hairobb__vn_le_bits(tn, hairobb__far_scale(tf));
}

/* The ray rotated once into the node's frame; rotation preserves t. */
static int hairobb__intersect_rotated_node(const hairobb__rotated_node *node, const hairobb__ray_state *rs, float dist[HAIROBB__W])
{
    hairobb__slab_ray slab;
    float org[3], dir[3], moved[3];
    int k;
    for (k = 0; k < 3; ++k) moved[k] = rs->line.org[k] - node->centre[k];
    for (k = 0; k < 3; ++k) {
        org[k] = hairobb__dot3(node->rotation + 3 * k, moved);
        dir[k] = hairobb__dot3(node->rotation + 3 * k, rs->line.dir);
    }
    hairobb__slab_setup(&slab, org, dir);
    return hairobb__intersect_boxes(node->lower[0], &slab, rs, dist);
}

/* Bytes decoded to the planes the builder checked; the ray moved to the
   node's centre, and rotated by the decoded frame for a rotated node. The
   byte planes lower[3][W], upper[3][W] are laid out as the float ones, so
   the slab ray's plane offsets index them too. */
HAIROBB__INLINE int hairobb__intersect_compressed_node(const hairobb__compressed_node *node, int rotated,
                                                       const signed char *end_planes, const hairobb__ray_state *rs,
                                                       float dist[HAIROBB__W])
{
    hairobb__slab_ray slab;
    hairobb__vn tn = hairobb__vn_set1(rs->line.tnear), tf = hairobb__vn_set1(rs->line.tfar), tau = hairobb__vn_set1(rs->line.time);
    const signed char *planes = node->lower[0];
    float moved[3];
    int k;
    for (k = 0; k < 3; ++k) moved[k] = rs->line.org[k] - node->centre[k];
    if (rotated) {
        float frame[9], org[3], dir[3];
        hairobb__decode_rotation(node->rotation, frame);
        for (k = 0; k < 3; ++k) {
            org[k] = hairobb__dot3(frame + 3 * k, moved);
            dir[k] = hairobb__dot3(frame + 3 * k, rs->line.dir);
        }
        hairobb__slab_setup(&slab, org, dir);
    } else {
        slab = rs->line.world;
        memcpy(slab.org, moved, sizeof moved);
    }
    for (k = 0; k < 3; ++k) {
        hairobb__vn o = hairobb__vn_set1(slab.org[k]), r = hairobb__vn_set1(slab.rdir[k]), step = hairobb__vn_set1(node->step[k]);
        hairobb__vn near_plane = hairobb__vn_from_bytes(planes + slab.near_plane[k]);
        hairobb__vn far_plane = hairobb__vn_from_bytes(planes + slab.far_plane[k]);
        if (end_planes) {   /* moving: the planes lerped to the ray's time, in steps */
            near_plane = hairobb__vn_add(near_plane, hairobb__vn_mul(tau, hairobb__vn_sub(hairobb__vn_from_bytes(end_planes + slab.near_plane[k]), near_plane)));
            far_plane = hairobb__vn_add(far_plane, hairobb__vn_mul(tau, hairobb__vn_sub(hairobb__vn_from_bytes(end_planes + slab.far_plane[k]), far_plane)));
        }
        near_plane = hairobb__vn_mul(near_plane, step);
        far_plane = hairobb__vn_mul(far_plane, step);
        tn = hairobb__vn_max(hairobb__vn_mul(hairobb__vn_sub(near_plane, o), r), tn);
        tf = hairobb__vn_min(hairobb__vn_mul(hairobb__vn_sub(far_plane, o), r), tf);
    }
    hairobb__vn_store(dist, tn);
    return hairobb__vn_le_bits(tn, hairobb__far_scale(tf));
}

/* Each child's rotation decoded as in the builder, the ray transformed per
   child (lanes), then slab tests against its decoded byte planes. 1/d is
   not clamped: where d = 0 it is +-inf, which puts t at +-inf (the ray
   outside or inside the slab, as it is), or at NaN on a plane, and min and
   max then keep the other operand (SSE's NaN rule, which the plain C twins
   share): a slab the ray runs along does not cut its interval. The axes are
   written out: a loop over them costs 4 instructions an axis. */
HAIROBB__INLINE int hairobb__intersect_compressed_obb_node(const hairobb__compressed_obb_node *node,
                                                           const signed char *end_planes, const hairobb__ray_state *rs,
                                                           float dist[HAIROBB__W])
{
    hairobb__vn tn = hairobb__vn_set1(rs->line.tnear), tf = hairobb__vn_set1(rs->line.tfar), tau = hairobb__vn_set1(rs->line.time);
    hairobb__vn ox = hairobb__vn_set1(rs->line.org[0] - node->centre[0]), oy = hairobb__vn_set1(rs->line.org[1] - node->centre[1]);
    hairobb__vn oz = hairobb__vn_set1(rs->line.org[2] - node->centre[2]);
    hairobb__vn dx = hairobb__vn_set1(rs->line.dir[0]), dy = hairobb__vn_set1(rs->line.dir[1]), dz = hairobb__vn_set1(rs->line.dir[2]);
    hairobb__vn one = hairobb__vn_set1(1.0f);
#define HAIROBB__QOBB_AXIS(k) do { \
        hairobb__vn m0 = hairobb__vn_from_bytes(node->rotation[3 * (k)]), m1 = hairobb__vn_from_bytes(node->rotation[3 * (k) + 1]); \
        hairobb__vn m2 = hairobb__vn_from_bytes(node->rotation[3 * (k) + 2]); \
        hairobb__vn o = hairobb__vn_add(hairobb__vn_add(hairobb__vn_mul(m0, ox), hairobb__vn_mul(m1, oy)), hairobb__vn_mul(m2, oz)); \
        hairobb__vn d = hairobb__vn_add(hairobb__vn_add(hairobb__vn_mul(m0, dx), hairobb__vn_mul(m1, dy)), hairobb__vn_mul(m2, dz)); \
        hairobb__vn r = hairobb__vn_div(one, d), step = hairobb__vn_set1(node->step[k]); \
        hairobb__vn lo = hairobb__vn_from_bytes(node->lower[k]), hi = hairobb__vn_from_bytes(node->upper[k]), t0, t1; \
        if (end_planes) {   /* moving: the planes lerped to the ray's time, in steps */ \
            lo = hairobb__vn_add(lo, hairobb__vn_mul(tau, hairobb__vn_sub(hairobb__vn_from_bytes(end_planes + (k) * HAIROBB__W), lo))); \
            hi = hairobb__vn_add(hi, hairobb__vn_mul(tau, hairobb__vn_sub(hairobb__vn_from_bytes(end_planes + (3 + (k)) * HAIROBB__W), hi))); \
        } \
        t0 = hairobb__vn_mul(hairobb__vn_sub(hairobb__vn_mul(lo, step), o), r); \
        t1 = hairobb__vn_mul(hairobb__vn_sub(hairobb__vn_mul(hi, step), o), r); \
        tn = hairobb__vn_max(hairobb__vn_min(t0, t1), tn); \
        tf = hairobb__vn_min(hairobb__vn_max(t0, t1), tf); \
    } while (0)
    HAIROBB__QOBB_AXIS(0);
    HAIROBB__QOBB_AXIS(1);
    HAIROBB__QOBB_AXIS(2);
#undef HAIROBB__QOBB_AXIS
    hairobb__vn_store(dist, tn);
    return hairobb__vn_le_bits(tn, hairobb__far_scale(tf));
}

/* Each child's slab pair along a row of its map is [0, 1] in unit space;
   1/d unclamped, as in hairobb__intersect_compressed_obb_node. */
HAIROBB__INLINE int hairobb__intersect_obb_node(const hairobb__obb_node *node, const hairobb__ray_state *rs, float dist[HAIROBB__W])
{
    hairobb__vn tn = hairobb__vn_set1(rs->line.tnear), tf = hairobb__vn_set1(rs->line.tfar);
    hairobb__vn one = hairobb__vn_set1(1.0f), zero = hairobb__vn_set1(0.0f);
    hairobb__vn ox = hairobb__vn_set1(rs->line.org[0] - node->centre[0]), oy = hairobb__vn_set1(rs->line.org[1] - node->centre[1]);
    hairobb__vn oz = hairobb__vn_set1(rs->line.org[2] - node->centre[2]);
    hairobb__vn dx = hairobb__vn_set1(rs->line.dir[0]), dy = hairobb__vn_set1(rs->line.dir[1]), dz = hairobb__vn_set1(rs->line.dir[2]);
#define HAIROBB__OBB_ROW(row) do { \
        hairobb__vn m0 = hairobb__vn_load(node->xfm[3 * (row)]), m1 = hairobb__vn_load(node->xfm[3 * (row) + 1]); \
        hairobb__vn m2 = hairobb__vn_load(node->xfm[3 * (row) + 2]), m3 = hairobb__vn_load(node->xfm[9 + (row)]); \
        hairobb__vn o = hairobb__vn_add(hairobb__vn_add(hairobb__vn_add(hairobb__vn_mul(m0, ox), hairobb__vn_mul(m1, oy)), hairobb__vn_mul(m2, oz)), m3); \
        hairobb__vn d = hairobb__vn_add(hairobb__vn_add(hairobb__vn_mul(m0, dx), hairobb__vn_mul(m1, dy)), hairobb__vn_mul(m2, dz)); \
        hairobb__vn r = hairobb__vn_div(one, d); \
        hairobb__vn t0 = hairobb__vn_mul(hairobb__vn_sub(zero, o), r); \
        hairobb__vn t1 = hairobb__vn_mul(hairobb__vn_sub(one, o), r); \
        tn = hairobb__vn_max(hairobb__vn_min(t0, t1), tn); \
        tf = hairobb__vn_min(hairobb__vn_max(t0, t1), tf); \
    } while (0)
    HAIROBB__OBB_ROW(0);
    HAIROBB__OBB_ROW(1);
    HAIROBB__OBB_ROW(2);
#undef HAIROBB__OBB_ROW
    hairobb__vn_store(dist, tn);
    return hairobb__vn_le_bits(tn, hairobb__far_scale(tf));
}

/* A child pushed on the stack waits at least one node test: its first lines
   (a node's planes; a leaf's first copied segment) are asked for now. */
HAIROBB__INLINE void hairobb__prefetch_child(const hairobb_bvh *bvh, uint64_t ref)
{
    if (HAIROBB__REF_TYPE(ref) == HAIROBB__REF_LEAF) {
        if (bvh->leaf_points) HAIROBB__PREFETCH(bvh->leaf_points + 16 * (size_t)(ref >> 8));
    } else {
        const unsigned char *node = HAIROBB__NODE_AT(bvh->nodes, ref);
        HAIROBB__PREFETCH(node);
        HAIROBB__PREFETCH(node + 64);
        HAIROBB__PREFETCH(node + 128);
    }
}

/* The node types other than the default layout's (per-child compressed
   OBB, AABB) and leaves: out of line, so that the loop tests its three
   common types with two well-predicted compares instead of a jump table. */
static HAIROBB__NOINLINE int hairobb__intersect_other_node(const hairobb_bvh *bvh, const hairobb__ray_state *rs, uint64_t ref,
                                                           float dist[HAIROBB__W], const uint64_t **child)
{
    unsigned type = HAIROBB__REF_TYPE(ref);
    const void *node;
    if (type == HAIROBB__REF_EMPTY) {
        *child = NULL;
        return 0;
    }
    node = HAIROBB__NODE_AT(bvh->nodes, ref);
    if (type == HAIROBB__REF_QAABB || type == HAIROBB__REF_QOBB) {
        *child = HAIROBB__CAST(const hairobb__compressed_node *, node)->child;
        return hairobb__intersect_compressed_node(HAIROBB__CAST(const hairobb__compressed_node *, node), type == HAIROBB__REF_QOBB,
                                                  NULL, rs, dist);
    }
    if (type == HAIROBB__REF_ROTATED) {
        *child = HAIROBB__CAST(const hairobb__rotated_node *, node)->child;
        return hairobb__intersect_rotated_node(HAIROBB__CAST(const hairobb__rotated_node *, node), rs, dist);
    }
    if (type == HAIROBB__REF_QOBB_PER_CHILD_MB) {   /* moving hair's nodes: the planes at time 1 follow */
        *child = HAIROBB__CAST(const hairobb__compressed_obb_node *, node)->child;
        return hairobb__intersect_compressed_obb_node(HAIROBB__CAST(const hairobb__compressed_obb_node *, node),
                                                      HAIROBB__CAST(const signed char *, node) + sizeof(hairobb__compressed_obb_node), rs, dist);
    }
    if (type == HAIROBB__REF_QAABB_MB || type == HAIROBB__REF_QOBB_MB) {
        *child = HAIROBB__CAST(const hairobb__compressed_node *, node)->child;
        return hairobb__intersect_compressed_node(HAIROBB__CAST(const hairobb__compressed_node *, node), type == HAIROBB__REF_QOBB_MB,
                                                  HAIROBB__CAST(const signed char *, node) + sizeof(hairobb__compressed_node), rs, dist);
    }
    *child = HAIROBB__CAST(const hairobb__obb_node *, node)->child;
    return hairobb__intersect_obb_node(HAIROBB__CAST(const hairobb__obb_node *, node), rs, dist);
}

/* Nearest-first traversal; any_hit stops at the first hit. A node with
   several hit children pushes them all, sorted so that the nearest is on
   top, and goes on with that one. */
static int hairobb__traverse(const hairobb_bvh *bvh, hairobb__ray_state *rs, int any_hit)
{
    uint64_t stack_ref[HAIROBB__STACK];
    float stack_dist[HAIROBB__STACK];
    int sp = 0, found = 0;
    uint64_t ref = bvh->root;
    rs->call.any_hit = any_hit;
    for (;;) {
        /* the default layout's types and leaves first, a compare each; the rest out of line */
        unsigned type = HAIROBB__REF_TYPE(ref);
        const void *node;   /* set for inner nodes only: a one-leaf tree has no node memory */
        const uint64_t *child;
        float dist[HAIROBB__W];
        int bits, i;
        if (type == HAIROBB__REF_QOBB_PER_CHILD) {
            node = HAIROBB__NODE_AT(bvh->nodes, ref);
            bits = hairobb__intersect_compressed_obb_node(HAIROBB__CAST(const hairobb__compressed_obb_node *, node), NULL, rs, dist);
            child = HAIROBB__CAST(const hairobb__compressed_obb_node *, node)->child;
        } else if (type == HAIROBB__REF_LEAF) {
            HAIROBB__COUNT(leaf);
            if (hairobb__intersect_leaf(bvh, rs, ref, any_hit)) {
                found = 1;
                if (any_hit) return 1;
            }
            bits = 0;
            child = NULL;
        } else if (type == HAIROBB__REF_AABB) {
            const hairobb__aabb_node *aabb = HAIROBB__CAST(const hairobb__aabb_node *, (const void *)HAIROBB__NODE_AT(bvh->nodes, ref));
            bits = hairobb__intersect_boxes(aabb->lower[0], &rs->line.world, rs, dist);
            child = aabb->child;
        } else {
            bits = hairobb__intersect_other_node(bvh, rs, ref, dist, &child);
        }
        if (child) HAIROBB__COUNT(node);
        if (bits) {
            int base = sp;
            unsigned rest = (unsigned)bits & ((unsigned)bits - 1u);
            if (!(rest & (rest - 1u))) {
                /* one or two hit children (most visits that hit any):
                   which of the two it is picks values,
                   not a branch; the farther one is pushed, and taken off
                   at once where it is the nearer (one hit) */
                int a = hairobb__lowest_bit((unsigned)bits), b = hairobb__highest_bit((unsigned)bits);
                int a_first = dist[a] < dist[b];      /* as the sort below orders them */
                stack_ref[sp] = a_first ? child[b] : child[a];
                stack_dist[sp] = a_first ? dist[b] : dist[a];
                ref = a_first ? child[a] : child[b];
                sp += rest != 0;
                continue;
            }
            i = hairobb__lowest_bit((unsigned)bits);
            bits &= bits - 1;
            if (any_hit) {
                /* any hit ends the ray: the nearest child goes first (on
                   crossing hair unsorted order cost a fifth of the shadow
                   rays' speed), the others wait unsorted */
                float nearest = dist[i];
                ref = child[i];
                do {
                    int j = hairobb__lowest_bit((unsigned)bits);
                    int nearer = dist[j] < nearest;
                    bits &= bits - 1;
                    stack_ref[sp] = nearer ? ref : child[j];
                    stack_dist[sp] = nearer ? nearest : dist[j];
                    hairobb__prefetch_child(bvh, stack_ref[sp]);
                    ref = nearer ? child[j] : ref;
                    nearest = nearer ? dist[j] : nearest;
                    ++sp;
                } while (bits);
                continue;
            }
            /* three or more: onto the stack sorted, nearest on top, equal
               distances in child order (the higher index above). Each
               child's place is its rank, the hit children farther than it
               or as near with a lower index, counted by two compares over
               the node's lanes: no branch on the distances, where an
               insertion sort mispredicts about once a child */
            {
                hairobb__vn lanes = hairobb__vn_load(dist);
                unsigned hits = (unsigned)bits | (1u << i), left = hits;
                do {
                    int j = hairobb__lowest_bit(left);
                    hairobb__vn dj = hairobb__vn_set1(dist[j]);
                    unsigned not_nearer = (unsigned)hairobb__vn_le_bits(dj, lanes);
                    unsigned not_farther = (unsigned)hairobb__vn_le_bits(lanes, dj);
                    int at = base + hairobb__bit_count(not_nearer & ~(not_farther & ~((1u << j) - 1u)) & hits);
                    left &= left - 1u;
                    stack_ref[at] = child[j];
                    stack_dist[at] = dist[j];
                    hairobb__prefetch_child(bvh, child[j]);
                } while (left);
                sp = base + hairobb__bit_count(hits) - 1;
            }
            ref = stack_ref[sp];
            continue;
        }
        /* widened as the node tests widen tfar: a child pushed before tfar
           shrank is dropped only where its test would now cull it, so the
           hits found do not depend on the order children are visited in */
        do {
            if (sp == 0) return found;
            --sp;
        } while (stack_dist[sp] > rs->line.tfar * HAIROBB__FAR_SCALE);
        ref = stack_ref[sp];
    }
}

#ifndef HAIROBB__KERNEL_PASS
/* ------------------------------------------------------------------------ */
/* >>tracing_api  Tracing API                                               */
/* ------------------------------------------------------------------------ */
#if HAIROBB__DISPATCH
HAIROBB__TARGET_AVX2 static int hairobb__traverse_avx2(const hairobb_bvh *bvh, hairobb__ray_state *rs, int any_hit);
#endif

/* The traversal of the BVH's path (every path gives the same answers). */
static int hairobb__trace(const hairobb_bvh *bvh, hairobb__ray_state *rs, int any_hit)
{
#if HAIROBB__DISPATCH
    if (bvh->simd == HAIROBB_SIMD_AVX2) return hairobb__traverse_avx2(bvh, rs, any_hit);
#endif
    return hairobb__traverse(bvh, rs, any_hit);
}

/* The filters a call shows its hits: the BVH's for its kind, the call's. */
HAIROBB__INLINE void hairobb__set_filters(hairobb__ray_state *rs, const hairobb_bvh *bvh, const hairobb_context *context, int any_hit)
{
    rs->call.hit_filter = any_hit ? bvh->occluded_filter : bvh->hit_filter;
    rs->call.hit_filter_user = any_hit ? bvh->occluded_filter_user : bvh->hit_filter_user;
    rs->call.call_filter = context ? context->filter : NULL;
    rs->call.call_filter_user = context ? context->user : NULL;
    rs->call.filtering = rs->call.hit_filter != NULL || rs->call.call_filter != NULL;
    rs->shown.count[0] = rs->shown.count[1] = 0;
    if (!HAIROBB__LIKELY(bvh->group_first == NULL)) {   /* groups: does the ray's mask exclude one? */
        uint32_t g;
        rs->call.ray_mask = context && context->mask ? context->mask : 0xffffffffu;
        rs->call.bvh_groups = bvh;
        if (!(rs->call.ray_mask & bvh->group_mask_and))
            for (g = 0; g < bvh->group_count && !rs->call.group_masked; ++g) rs->call.group_masked = !(bvh->group_mask[g] & rs->call.ray_mask);
    }
}

HAIROBB_DEF int hairobb_intersect1_context(const hairobb_bvh *bvh, const hairobb_context *context, const hairobb_hit *from,
                                           const hairobb_ray *ray, hairobb_hit *hit)
{
    hairobb__ray_state rs;
    int ready;
    if (!hit) return 0;
    /* `from` is read (into rs) before *hit is written: the two may be one
       hit, as a path tracer's loop passes them */
    ready = bvh && ray && hairobb__ray_setup_from(&rs, bvh, from, ray);
    hit->prim_id = hit->instance_id = hit->group_id = HAIROBB_INVALID_ID;
    if (!ready) return 0;
    hairobb__set_filters(&rs, bvh, context, 0);
    if (!hairobb__trace(bvh, &rs, 0)) return 0;
    hairobb__hit_at(bvh, &rs, rs.best.prim, rs.best.points, &rs.best.curve, rs.best.u, rs.line.tfar, rs.best.cap, hit);
    return 1;
}

HAIROBB_DEF int hairobb_occluded1_context(const hairobb_bvh *bvh, const hairobb_context *context, const hairobb_hit *from,
                                          const hairobb_ray *ray)
{
    hairobb__ray_state rs;
    if (!bvh || !ray || !hairobb__ray_setup_from(&rs, bvh, from, ray)) return 0;
    hairobb__set_filters(&rs, bvh, context, 1);
    return hairobb__trace(bvh, &rs, 1);
}

HAIROBB_DEF int hairobb_intersect1_from(const hairobb_bvh *bvh, const hairobb_hit *from, const hairobb_ray *ray,
                                        hairobb_hit *hit)
{
    return hairobb_intersect1_context(bvh, NULL, from, ray, hit);
}

HAIROBB_DEF int hairobb_occluded1_from(const hairobb_bvh *bvh, const hairobb_hit *from, const hairobb_ray *ray)
{
    return hairobb_occluded1_context(bvh, NULL, from, ray);
}

HAIROBB_DEF int hairobb_intersect1(const hairobb_bvh *bvh, const hairobb_ray *ray, hairobb_hit *hit)
{
    return hairobb_intersect1_from(bvh, NULL, ray, hit);
}

HAIROBB_DEF int hairobb_occluded1(const hairobb_bvh *bvh, const hairobb_ray *ray)
{
    return hairobb_occluded1_from(bvh, NULL, ray);
}

HAIROBB_DEF hairobb_simd hairobb_get_simd(const hairobb_bvh *bvh)
{
    return bvh ? bvh->simd : HAIROBB_SIMD_NONE;
}

/* ------------------------------------------------------------------------ */
/* >>scene  Several hair groups: instances under a top level                */
/* ------------------------------------------------------------------------ */
/* A scene keeps each instance's maps both ways and its world box, and a
   binary tree over those boxes (one instance a leaf, median splits on the
   widest axis of the centres: scenes hold tens to thousands of instances,
   a small part of a ray's work). A ray is taken into each instance it
   reaches (t is the same parameter in both spaces: the map is affine and
   dir is not normalised) and traced there with tfar the nearest hit so
   far; ties in t go to the lower instance id. */
typedef struct hairobb__scene_node {
    float lower[3], upper[3];
    uint32_t index, count;   /* count 1: the leaf of order[index]; 0: children at index, index + 1 */
} hairobb__scene_node;

struct hairobb_scene {
    void *allocator_user;
    size_t count;
    hairobb__placed *placed;
    uint32_t *order;               /* instance ids in tree order */
    hairobb__scene_node *nodes;    /* 2 count - 1 of them, the root first */
};

/* The inverse of the affine map m (3 rows of 4) into inverse, in double;
   0 where m is not finite or (nearly) singular. */
static int hairobb__affine_inverse(const float m[12], float inverse[12])
{
    double a[3][3], adj[3][3], det, scale = 0.0, out[12];
    int i, j;
    for (i = 0; i < 12; ++i) {
        if (!(fabsf(m[i]) <= HAIROBB__MAX_COORD)) return 0;   /* NaN, Inf, or beyond the input's range */
    }
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            a[i][j] = m[4 * i + j];
            if (fabs(a[i][j]) > scale) scale = fabs(a[i][j]);
        }
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            adj[i][j] = a[i1][j1] * a[i2][j2] - a[i1][j2] * a[i2][j1];   /* cofactor (j, i) */
        }
    det = a[0][0] * adj[0][0] + a[0][1] * adj[1][0] + a[0][2] * adj[2][0];
    /* below 2^-40 of the largest entry cubed: no float map back */
    if (!(fabs(det) > scale * scale * scale * 9.094947017729282e-13)) return 0;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) out[4 * i + j] = adj[i][j] / det;
        out[4 * i + 3] = -(out[4 * i] * m[3] + out[4 * i + 1] * m[7] + out[4 * i + 2] * m[11]);
    }
    for (i = 0; i < 12; ++i) {
        if (!(fabs(out[i]) <= 1e30)) return 0;
        inverse[i] = (float)out[i];
    }
    return 1;
}

/* An instance checked and placed: its maps, mask and world box (the BVH's
   box mapped, in double, and widened by the rounding of float). */
static hairobb_result hairobb__place(const hairobb_instance *instance, hairobb__placed *placed)
{
    float lower[3], upper[3];
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, magnitude = 0.0;
    int corner, i;
    if (!instance->bvh) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (!hairobb__affine_inverse(instance->transform, placed->to_object)) return HAIROBB_ERROR_INVALID_ARGUMENT;
    memcpy(placed->to_world, instance->transform, sizeof placed->to_world);
    placed->bvh = instance->bvh;
    placed->mask = instance->mask ? instance->mask : 0xffffffffu;
    placed->user = instance->user;
    hairobb_bounds(instance->bvh, lower, upper);
    for (corner = 0; corner < 8; ++corner) {
        double p[3];
        p[0] = corner & 1 ? upper[0] : lower[0];
        p[1] = corner & 2 ? upper[1] : lower[1];
        p[2] = corner & 4 ? upper[2] : lower[2];
        for (i = 0; i < 3; ++i) {
            const float *row = instance->transform + 4 * i;
            double w = row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3];
            if (w < lo[i]) lo[i] = w;
            if (w > hi[i]) hi[i] = w;
        }
    }
    for (i = 0; i < 3; ++i) magnitude = fmax(magnitude, fmax(fabs(lo[i]), fabs(hi[i])));
    for (i = 0; i < 3; ++i) {
        /* the tracing maps the ray, not the box: widened by the rounding of
           a map in float (a few ulps of the largest coordinate) */
        double pad = magnitude * (64.0 * FLT_EPSILON) + 1e-30;
        placed->lower[i] = (float)(lo[i] - pad);
        placed->upper[i] = (float)(hi[i] + pad);
    }
    if (!(magnitude < 1e30)) return HAIROBB_ERROR_INVALID_ARGUMENT;
    return HAIROBB_OK;
}

static float hairobb__placed_centre(const hairobb__placed *p, int axis) { return 0.5f * (p->lower[axis] + p->upper[axis]); }

/* order[begin, end) rearranged so that its middle entry has the middle
   centre on axis, the lower ones before it (quickselect). */
static void hairobb__select_middle(const hairobb__placed *placed, uint32_t *order, size_t begin, size_t end, int axis)
{
    size_t middle = begin + (end - begin) / 2;
    while (end - begin > 1) {
        float pivot = hairobb__placed_centre(&placed[order[begin + (end - begin) / 2]], axis);
        size_t low = begin, high = end - 1, k = begin;
        /* three-way partition: below, equal, above the pivot */
        while (k <= high) {
            float c = hairobb__placed_centre(&placed[order[k]], axis);
            uint32_t swap;
            if (c < pivot) {
                swap = order[low]; order[low] = order[k]; order[k] = swap;
                ++low;
                ++k;
            } else if (c > pivot) {
                swap = order[high]; order[high] = order[k]; order[k] = swap;
                if (high == 0) break;
                --high;
            } else {
                ++k;
            }
        }
        if (middle < low) end = low;
        else if (middle > high) begin = high + 1;
        else return;
    }
}

/* The tree over order[begin, end) at nodes[at]; children at *next on. */
static void hairobb__scene_tree(hairobb_scene *scene, size_t at, size_t begin, size_t end, size_t *next)
{
    hairobb__scene_node *node = &scene->nodes[at];
    float lo[3], hi[3];
    size_t i, middle;
    int k, axis = 0;
    for (k = 0; k < 3; ++k) {
        node->lower[k] = lo[k] = INFINITY;
        node->upper[k] = hi[k] = -INFINITY;
    }
    for (i = begin; i < end; ++i) {
        const hairobb__placed *p = &scene->placed[scene->order[i]];
        for (k = 0; k < 3; ++k) {
            node->lower[k] = hairobb__minf(node->lower[k], p->lower[k]);
            node->upper[k] = hairobb__maxf(node->upper[k], p->upper[k]);
            lo[k] = hairobb__minf(lo[k], hairobb__placed_centre(p, k));
            hi[k] = hairobb__maxf(hi[k], hairobb__placed_centre(p, k));
        }
    }
    if (end - begin == 1) {
        node->index = (uint32_t)begin;
        node->count = 1;
        return;
    }
    for (k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    hairobb__select_middle(scene->placed, scene->order, begin, end, axis);
    middle = begin + (end - begin) / 2;
    node->index = (uint32_t)*next;
    node->count = 0;
    *next += 2;
    hairobb__scene_tree(scene, node->index, begin, middle, next);
    hairobb__scene_tree(scene, (size_t)node->index + 1, middle, end, next);
}

/* The instances checked into placed (count of them), then the tree. */
static hairobb_result hairobb__scene_fill(hairobb_scene *scene, const hairobb_instance *instances)
{
    size_t i, next = 1;
    for (i = 0; i < scene->count; ++i) {
        hairobb__placed check;
        hairobb_result result = hairobb__place(&instances[i], &check);
        if (result != HAIROBB_OK) return result;
    }
    for (i = 0; i < scene->count; ++i) {
        (void)hairobb__place(&instances[i], &scene->placed[i]);
        scene->order[i] = (uint32_t)i;
    }
    if (scene->count) hairobb__scene_tree(scene, 0, 0, scene->count, &next);
    return HAIROBB_OK;
}

HAIROBB_DEF void hairobb_scene_free(hairobb_scene *scene)
{
    if (!scene) return;
    HAIROBB_FREE(scene->placed, scene->allocator_user);
    HAIROBB_FREE(scene->order, scene->allocator_user);
    HAIROBB_FREE(scene->nodes, scene->allocator_user);
    HAIROBB_FREE(scene, scene->allocator_user);
}

HAIROBB_DEF hairobb_result hairobb_scene_build(const hairobb_instance *instances, size_t count, void *allocator_user,
                                               hairobb_scene **out)
{
    hairobb_scene *scene;
    hairobb_result result;
    if (out) *out = NULL;
    if (!out || (count && !instances)) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (count > 0x7fffffffu) return HAIROBB_ERROR_TOO_LARGE;
    scene = HAIROBB__CAST(hairobb_scene *, HAIROBB_MALLOC(sizeof *scene, allocator_user));
    if (!scene) return HAIROBB_ERROR_OUT_OF_MEMORY;
    memset(scene, 0, sizeof *scene);
    scene->allocator_user = allocator_user;
    scene->count = count;
    if (count) {
        scene->placed = HAIROBB__CAST(hairobb__placed *, HAIROBB_MALLOC(count * sizeof *scene->placed, allocator_user));
        scene->order = HAIROBB__CAST(uint32_t *, HAIROBB_MALLOC(count * sizeof *scene->order, allocator_user));
        scene->nodes = HAIROBB__CAST(hairobb__scene_node *, HAIROBB_MALLOC((2 * count - 1) * sizeof *scene->nodes, allocator_user));
        if (!scene->placed || !scene->order || !scene->nodes) {
            hairobb_scene_free(scene);
            return HAIROBB_ERROR_OUT_OF_MEMORY;
        }
    }
    result = hairobb__scene_fill(scene, instances);
    if (result != HAIROBB_OK) {
        hairobb_scene_free(scene);
        return result;
    }
    *out = scene;
    return HAIROBB_OK;
}

HAIROBB_DEF hairobb_result hairobb_scene_update(hairobb_scene *scene, const hairobb_instance *instances, size_t count)
{
    hairobb_scene *fresh, old;
    hairobb_result result;
    if (!scene || (count && !instances)) return HAIROBB_ERROR_INVALID_ARGUMENT;
    if (count == scene->count) return hairobb__scene_fill(scene, instances);   /* checks every instance before it changes any */
    /* another count: a scene built anew takes this one's place (on an
       error this one is as it was) */
    result = hairobb_scene_build(instances, count, scene->allocator_user, &fresh);
    if (result != HAIROBB_OK) return result;
    old = *scene;
    *scene = *fresh;
    *fresh = old;
    hairobb_scene_free(fresh);
    return HAIROBB_OK;
}

HAIROBB_DEF size_t hairobb_scene_count(const hairobb_scene *scene)
{
    return scene ? scene->count : 0;
}

HAIROBB_DEF void hairobb_scene_bounds(const hairobb_scene *scene, float lower[3], float upper[3])
{
    int k;
    if (!lower || !upper) return;
    for (k = 0; k < 3; ++k) {
        lower[k] = scene && scene->count ? scene->nodes[0].lower[k] : INFINITY;
        upper[k] = scene && scene->count ? scene->nodes[0].upper[k] : -INFINITY;
    }
}

HAIROBB_DEF size_t hairobb_scene_memory_bytes(const hairobb_scene *scene)
{
    if (!scene) return 0;
    return sizeof *scene + scene->count * (sizeof *scene->placed + sizeof *scene->order) +
           (scene->count ? (2 * scene->count - 1) * sizeof *scene->nodes : 0);
}

HAIROBB_DEF void *hairobb_scene_user(const hairobb_scene *scene, uint32_t instance_id)
{
    return scene && instance_id < scene->count ? scene->placed[instance_id].user : NULL;
}

/* The ray in an instance's object space: the same t, tnear, tfar, time.
   Mapped in double and rounded once: in float the origin's rounding (a
   few ulps of its distance, 10 units away about 1e-6) reached 4e-3 of a
   fine hair's radius in t. */
static void hairobb__ray_to_object(const hairobb__placed *placed, const hairobb_ray *ray, hairobb_ray *object)
{
    const float *m = placed->to_object;
    int i;
    for (i = 0; i < 3; ++i) {
        object->org[i] = (float)((double)m[4 * i] * ray->org[0] + (double)m[4 * i + 1] * ray->org[1] +
                                 (double)m[4 * i + 2] * ray->org[2] + (double)m[4 * i + 3]);
        object->dir[i] = (float)((double)m[4 * i] * ray->dir[0] + (double)m[4 * i + 1] * ray->dir[1] + (double)m[4 * i + 2] * ray->dir[2]);
    }
    object->tnear = ray->tnear;
    object->tfar = ray->tfar;
    object->time = ray->time;
}

/* The world box's slab test, [tnear, tfar] against it (a zero direction
   component: the origin within the slab). */
static int hairobb__scene_box(const float lower[3], const float upper[3], const float org[3], const float inv_dir[3],
                              const float dir[3], float tnear, float tfar)
{
    int k;
    for (k = 0; k < 3; ++k) {
        float t0, t1;
        if (dir[k] == 0.0f) {
            if (org[k] < lower[k] || org[k] > upper[k]) return 0;
            continue;
        }
        t0 = (lower[k] - org[k]) * inv_dir[k];
        t1 = (upper[k] - org[k]) * inv_dir[k];
        tnear = hairobb__maxf(tnear, hairobb__minf(t0, t1));
        tfar = hairobb__minf(tfar, hairobb__maxf(t0, t1));
    }
    return tnear <= tfar * HAIROBB__FAR_SCALE;
}

/* Each instance the ray reaches, nearest box first: visit(instance id)
   returns 1 to stop. The tfar the boxes are tested against is *tfar, read
   again at each step (it shrinks as hits are found). */
typedef struct hairobb__scene_walk {
    const hairobb_scene *scene;
    const hairobb_ray *ray;
    uint32_t mask;
    const float *tfar;
    float inv_dir[3];
} hairobb__scene_walk;

#define HAIROBB__SCENE_STACK 64   /* median splits: depth <= log2(2^31) + 1 */

static int hairobb__scene_next(hairobb__scene_walk *w, uint32_t *stack, int *sp, uint32_t *instance)
{
    const hairobb_scene *scene = w->scene;
    while (*sp > 0) {
        const hairobb__scene_node *node = &scene->nodes[stack[--*sp]];
        if (!hairobb__scene_box(node->lower, node->upper, w->ray->org, w->inv_dir, w->ray->dir, w->ray->tnear, *w->tfar)) continue;
        if (node->count) {
            uint32_t id = scene->order[node->index];
            if (!(scene->placed[id].mask & w->mask)) continue;
            *instance = id;
            return 1;
        } else {
            /* the nearer child (by its box's centre along the ray) on top */
            const hairobb__scene_node *a = &scene->nodes[node->index], *b = a + 1;
            float da = 0.0f, db = 0.0f;
            int k;
            for (k = 0; k < 3; ++k) {
                da += (a->lower[k] + a->upper[k]) * w->ray->dir[k];
                db += (b->lower[k] + b->upper[k]) * w->ray->dir[k];
            }
            stack[(*sp)++] = da < db ? node->index + 1 : node->index;
            stack[(*sp)++] = da < db ? node->index : node->index + 1;
        }
    }
    return 0;
}

static int hairobb__scene_walk_start(hairobb__scene_walk *w, const hairobb_scene *scene, const hairobb_context *context,
                                     const hairobb_ray *ray, const float *tfar)
{
    int k;
    w->scene = scene;
    w->ray = ray;
    w->mask = context && context->mask ? context->mask : 0xffffffffu;
    w->tfar = tfar;
    for (k = 0; k < 3; ++k) w->inv_dir[k] = ray->dir[k] != 0.0f ? 1.0f / ray->dir[k] : 0.0f;
    return scene->count > 0 && ray->tnear <= ray->tfar;
}

/* `from` as the instance's own ray would have it: Ng back in object space
   (by the transpose of the object-to-world map, which keeps its sign
   against any direction mapped alike). */
static void hairobb__from_to_object(const hairobb__placed *placed, const hairobb_hit *from, hairobb_hit *object)
{
    const float *m = placed->to_world;
    int i;
    *object = *from;
    for (i = 0; i < 3; ++i) object->Ng[i] = m[i] * from->Ng[0] + m[4 + i] * from->Ng[1] + m[8 + i] * from->Ng[2];
}

/* The ray traced in instance id, tfar its own; 0 where it cannot be (a
   direction the map sends to 0 or out of range). */
static int hairobb__scene_trace(const hairobb_scene *scene, uint32_t id, const hairobb_context *context, const hairobb_hit *from,
                                const hairobb_ray *ray, float tfar, int any_hit, hairobb__ray_state *rs)
{
    const hairobb__placed *placed = &scene->placed[id];
    hairobb_ray object;
    hairobb_hit from_object;
    const hairobb_hit *leaving = NULL;
    hairobb__ray_to_object(placed, ray, &object);
    object.tfar = tfar;
    if (from && from->instance_id == id) {
        hairobb__from_to_object(placed, from, &from_object);
        leaving = &from_object;
    }
    if (!hairobb__ray_setup_from(rs, placed->bvh, leaving, &object)) return 0;
    rs->call.ray = ray;   /* filters are shown the caller's ray, and hits in world space */
    rs->call.placed = placed;
    rs->call.instance_id = id;
    hairobb__set_filters(rs, placed->bvh, context, any_hit);
    return hairobb__trace(placed->bvh, rs, any_hit);
}

HAIROBB_DEF int hairobb_scene_intersect1(const hairobb_scene *scene, const hairobb_context *context, const hairobb_hit *from,
                                         const hairobb_ray *ray, hairobb_hit *hit)
{
    hairobb__scene_walk walk;
    hairobb__ray_state rs;
    hairobb_hit best, leaving;
    uint32_t stack[HAIROBB__SCENE_STACK], id, best_id = HAIROBB_INVALID_ID;
    float best_t;
    int sp = 1;
    if (!hit) return 0;
    if (from) leaving = *from;   /* read before *hit is written: they may be one hit */
    hit->prim_id = hit->instance_id = hit->group_id = HAIROBB_INVALID_ID;
    if (!scene || !ray) return 0;
    best_t = ray->tfar;
    if (!hairobb__scene_walk_start(&walk, scene, context, ray, &best_t)) return 0;
    stack[0] = 0;
    while (hairobb__scene_next(&walk, stack, &sp, &id)) {
        if (!hairobb__scene_trace(scene, id, context, from ? &leaving : NULL, ray, best_t, 0, &rs)) continue;
        if (best_id != HAIROBB_INVALID_ID && !(rs.line.tfar < best_t || (rs.line.tfar == best_t && id < best_id))) continue;
        hairobb__hit_at(scene->placed[id].bvh, &rs, rs.best.prim, rs.best.points, &rs.best.curve, rs.best.u, rs.line.tfar, rs.best.cap, &best);
        hairobb__hit_to_world(&scene->placed[id], id, &best);
        best_t = rs.line.tfar;
        best_id = id;
    }
    if (best_id == HAIROBB_INVALID_ID) return 0;
    *hit = best;
    return 1;
}

HAIROBB_DEF int hairobb_scene_occluded1(const hairobb_scene *scene, const hairobb_context *context, const hairobb_hit *from,
                                        const hairobb_ray *ray)
{
    hairobb__scene_walk walk;
    hairobb__ray_state rs;
    uint32_t stack[HAIROBB__SCENE_STACK], id;
    float tfar;
    int sp = 1;
    if (!scene || !ray) return 0;
    tfar = ray->tfar;
    if (!hairobb__scene_walk_start(&walk, scene, context, ray, &tfar)) return 0;
    stack[0] = 0;
    while (hairobb__scene_next(&walk, stack, &sp, &id))
        if (hairobb__scene_trace(scene, id, context, from, ray, tfar, 1, &rs)) return 1;
    return 0;
}

/* ------------------------------------------------------------------------ */
/* >>dispatch  Runtime dispatch: the kernels once more, for AVX2            */
/* ------------------------------------------------------------------------ */
/* The file includes itself (HAIROBB_SELF, found first in its own directory)
   with every name the kernels define suffixed _avx2: a name missing here is
   a redefinition error, and tests/check_dispatch_list.sh checks the list
   against the kernels both ways. Nothing follows, so the names need no
   #undef. No FMA: the paths round alike. */
#if HAIROBB__DISPATCH
#define hairobb__v4 hairobb__v4_avx2
#define hairobb__v8 hairobb__v8_avx2
#define hairobb__vn hairobb__vn_avx2
#define hairobb__accept hairobb__accept_avx2
#define hairobb__take hairobb__take_avx2
#define hairobb__tube_segment hairobb__tube_segment_avx2
#define hairobb__tube_point hairobb__tube_point_avx2
#define hairobb__tube_change hairobb__tube_change_avx2
#define hairobb__bit_count hairobb__bit_count_avx2
#define hairobb__ribbon_segment hairobb__ribbon_segment_avx2
#define hairobb__bezier_v4 hairobb__bezier_v4_avx2
#define hairobb__chord_pad hairobb__chord_pad_avx2
#define hairobb__converted_points hairobb__converted_points_avx2
#define hairobb__far_scale hairobb__far_scale_avx2
#define hairobb__hit_at hairobb__hit_at_avx2
#define hairobb__tube_hit_at hairobb__tube_hit_at_avx2
#define hairobb__hit_filtered_out hairobb__hit_filtered_out_avx2
#define hairobb__hit_to_world hairobb__hit_to_world_avx2
#define hairobb__normalize3 hairobb__normalize3_avx2
#define hairobb__ignored_before hairobb__ignored_before_avx2
#define hairobb__shares_end hairobb__shares_end_avx2
#define hairobb__horner hairobb__horner_avx2
#define hairobb__intersect_boxes hairobb__intersect_boxes_avx2
#define hairobb__intersect_compressed_node hairobb__intersect_compressed_node_avx2
#define hairobb__intersect_compressed_obb_node hairobb__intersect_compressed_obb_node_avx2
#define hairobb__intersect_curve hairobb__intersect_curve_avx2
#define hairobb__intersect_leaf hairobb__intersect_leaf_avx2
#define hairobb__intersect_obb_node hairobb__intersect_obb_node_avx2
#define hairobb__intersect_other_node hairobb__intersect_other_node_avx2
#define hairobb__intersect_rotated_node hairobb__intersect_rotated_node_avx2
#define hairobb__intersect_segment hairobb__intersect_segment_avx2
#define hairobb__intersect_tube hairobb__intersect_tube_avx2
#define hairobb__tube_at hairobb__tube_at_avx2
#define hairobb__tube_cap hairobb__tube_cap_avx2
#define hairobb__tube_joint hairobb__tube_joint_avx2
#define hairobb__tube_g hairobb__tube_g_avx2
#define hairobb__tube_hit hairobb__tube_hit_avx2
#define hairobb__tube_inside hairobb__tube_inside_avx2
#define hairobb__tube_root hairobb__tube_root_avx2
#define hairobb__tube_g_slope hairobb__tube_g_slope_avx2
#define hairobb__tube_root_unreachable hairobb__tube_root_unreachable_avx2
#define hairobb__tube_exits hairobb__tube_exits_avx2
#define hairobb__tube_edge hairobb__tube_edge_avx2
#define hairobb__tube_low hairobb__tube_low_avx2
#define hairobb__tube_q hairobb__tube_q_avx2
#define hairobb__tube_sample_u hairobb__tube_sample_u_avx2
#define hairobb__tube_q_v8 hairobb__tube_q_v8_avx2
#define hairobb__tube_square hairobb__tube_square_avx2
#define hairobb__v8_pick4 hairobb__v8_pick4_avx2
#define hairobb__v8_next hairobb__v8_next_avx2
#define hairobb__v4_next hairobb__v4_next_avx2
#define hairobb__horner_v8 hairobb__horner_v8_avx2
#define hairobb__tube_g_v8 hairobb__tube_g_v8_avx2
#define hairobb__ray_point hairobb__ray_point_avx2
#define hairobb__joint_at hairobb__joint_at_avx2
#define hairobb__made_moving hairobb__made_moving_avx2
#define hairobb__piece_ends hairobb__piece_ends_avx2
#define hairobb__piece_hit hairobb__piece_hit_avx2
#define hairobb__points_at hairobb__points_at_avx2
#define hairobb__prefetch_child hairobb__prefetch_child_avx2
#define hairobb__ray_points_v4 hairobb__ray_points_v4_avx2
#define hairobb__ray_row_v4 hairobb__ray_row_v4_avx2
#define hairobb__refine_dip hairobb__refine_dip_avx2
#define hairobb__refine_piece hairobb__refine_piece_avx2
#define hairobb__ribbon_f hairobb__ribbon_f_avx2
#define hairobb__ribbon_f_v8 hairobb__ribbon_f_v8_avx2
#define hairobb__segment_points hairobb__segment_points_avx2
#define hairobb__skipped hairobb__skipped_avx2
#define hairobb__same_group hairobb__same_group_avx2
#define hairobb__hit_ids hairobb__hit_ids_avx2
#define hairobb__solve_bracketed hairobb__solve_bracketed_avx2
#define hairobb__to_bezier hairobb__to_bezier_avx2
#define hairobb__to_power_form hairobb__to_power_form_avx2
#define hairobb__traverse hairobb__traverse_avx2
#define hairobb__try_end hairobb__try_end_avx2
#define hairobb__try_hit hairobb__try_hit_avx2
#define hairobb__polished_t hairobb__polished_t_avx2
#define hairobb__v4_abs hairobb__v4_abs_avx2
#define hairobb__v4_pairs hairobb__v4_pairs_avx2
#define hairobb__v4_sqrt hairobb__v4_sqrt_avx2
#define hairobb__v4_add hairobb__v4_add_avx2
#define hairobb__v4_div hairobb__v4_div_avx2
#define hairobb__v4_from_bytes hairobb__v4_from_bytes_avx2
#define hairobb__v4_hmax hairobb__v4_hmax_avx2
#define hairobb__v4_le_bits hairobb__v4_le_bits_avx2
#define hairobb__v4_lt_bits hairobb__v4_lt_bits_avx2
#define hairobb__v4_load hairobb__v4_load_avx2
#define hairobb__v4_max hairobb__v4_max_avx2
#define hairobb__v4_min hairobb__v4_min_avx2
#define hairobb__v4_mul hairobb__v4_mul_avx2
#define hairobb__v4_set1 hairobb__v4_set1_avx2
#define hairobb__v4_set3 hairobb__v4_set3_avx2
#define hairobb__v4_store hairobb__v4_store_avx2
#define hairobb__v4_sub hairobb__v4_sub_avx2
#define hairobb__v4_transpose hairobb__v4_transpose_avx2
#define hairobb__v8_add hairobb__v8_add_avx2
#define hairobb__v8_div hairobb__v8_div_avx2
#define hairobb__v8_from_bytes hairobb__v8_from_bytes_avx2
#define hairobb__v8_le_bits hairobb__v8_le_bits_avx2
#define hairobb__v8_lt_bits hairobb__v8_lt_bits_avx2
#define hairobb__v8_load hairobb__v8_load_avx2
#define hairobb__v8_max hairobb__v8_max_avx2
#define hairobb__v8_min hairobb__v8_min_avx2
#define hairobb__v8_mul hairobb__v8_mul_avx2
#define hairobb__v8_set1 hairobb__v8_set1_avx2
#define hairobb__v8_store hairobb__v8_store_avx2
#define hairobb__v8_sub hairobb__v8_sub_avx2
#undef HAIROBB__SSE41
#define HAIROBB__SSE41 1
#undef HAIROBB__AVX
#define HAIROBB__AVX 1
#undef HAIROBB__AVX2
#define HAIROBB__AVX2 1
#define HAIROBB__KERNEL_PASS 1
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#elif defined(__GNUC__)
#pragma GCC push_options
#pragma GCC target("avx2")
#endif
#ifndef HAIROBB_SELF
#define HAIROBB_SELF "hairobb.h"
#endif
#ifdef __has_include
#if !__has_include(HAIROBB_SELF)
#error "hairobb.h includes itself as HAIROBB_SELF for runtime dispatch: define HAIROBB_SELF to its file name, or HAIROBB_NO_DISPATCH"
#endif
#endif
#include HAIROBB_SELF
#if defined(__clang__)
#pragma clang attribute pop
#elif defined(__GNUC__)
#pragma GCC pop_options
#endif
#undef HAIROBB__KERNEL_PASS
#endif /* HAIROBB__DISPATCH */

#endif /* !HAIROBB__KERNEL_PASS */
#endif /* HAIROBB_IMPLEMENTATION_DONE || HAIROBB__KERNEL_PASS */
#endif /* HAIROBB_IMPLEMENTATION */

/* >>licence
------------------------------------------------------------------------------
This software is available under 2 licenses -- choose whichever you prefer.
------------------------------------------------------------------------------
ALTERNATIVE A - MIT License
Copyright (c) 2026 the hairobb authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:
The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
ALTERNATIVE B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.
In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication in the interest of the public and to the benefit
of the public at large and to the detriment of our heirs and successors. We
intend this dedication to be an overt act of relinquishment in perpetuity of
all present and future rights to this software under copyright law.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
*/
