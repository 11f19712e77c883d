// How closest-hit kernels write their answers into `hits` (array<u32>),
// for a module whose `params` has `count` and `tri_only`: with
// `tri_only` the triangles in words [0, count) and their t in
// [count, 2·count), so that the triangles read back alone and the hits can
// stay on the device; else (t, scene triangle) pairs. A miss is
// (NO_HIT, NONE).

fn write_hit(i: u32, t: f32, tri: u32) {
    if (params.tri_only != 0u) {
        hits[i] = tri;
        hits[params.count + i] = bitcast<u32>(t);
    } else {
        hits[2u * i] = bitcast<u32>(t);
        hits[2u * i + 1u] = tri;
    }
}
