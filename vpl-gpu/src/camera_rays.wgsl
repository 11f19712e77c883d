// Camera rays made on the device and cast: twin of vpl_core::CameraRays.
// Ray j draws (u, v) and then the lens sample from stream j under the key,
// and is the camera's ray through raster (u·w, v·h) (vpl_core::Camera::ray).
// Closest hits come back as (t, scene triangle) pairs, or (`tri_only`) as
// the triangle alone, as raycast.wgsl's.

struct Params {
    count: u32,
    row: u32,
    key_lo: u32,
    key_hi: u32,
    tri_only: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    origin: vec4<f32>,
    // xyz and, in w: s_x (forward), s_y (right), focus distance (up).
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // Width, height, lens radius (0: a pinhole), -.
    raster: vec4<f32>,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read_write> hits: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let j = id.x + id.y * params.row;
    if (j >= params.count) { return; }
    let r = keyed_state(vec2<u32>(params.key_lo, params.key_hi), j);
    rng_state = r.xy;
    rng_inc = r.zw;
    let w = params.raster.x;
    let h = params.raster.y;
    let u = next_f32();
    let v = next_f32();
    let lu = next_f32();
    let lv = next_f32();
    let ndc_x = 2.0 * (u * w) / w - 1.0;
    let ndc_y = 1.0 - 2.0 * (v * h) / h;
    let d = params.forward.xyz + params.right.xyz * (ndc_x * params.forward.w) + params.up.xyz * (ndc_y * params.right.w);
    var o = params.origin.xyz;
    var dir = normalize(d);
    if (params.raster.z > 0.0) {
        // Thin lens: from a point of the aperture toward the point in focus.
        let focus = o + d * params.up.w;
        let l = concentric_disk(lu, lv) * params.raster.z;
        o = o + params.right.xyz * l.x + params.up.xyz * l.y;
        dir = normalize(focus - o);
    }
    let hit = closest_hit(o, dir, NO_HIT);
    var t = NO_HIT;
    var tri = NONE;
    if (hit.prim != NONE) {
        t = hit.t;
        tri = bvh_order[hit.prim];
    }
    if (params.tri_only != 0u) {
        hits[j] = tri;
    } else {
        hits[2u * j] = bitcast<u32>(t);
        hits[2u * j + 1u] = tri;
    }
}
