// Camera rays made on the device and cast: twin of vpl_core::CameraRays.
// Ray j draws (u, v) and then the lens sample from stream j under the key,
// and is the camera's ray through raster (u·w, v·h) (vpl_core::Camera::ray).
// Closest hits come back as hits.wgsl writes them; with `tri_only` the
// hits stay on the device for `bounce`.
//
// `bounce`: twin of vpl_core::BounceRays. Ray k leaves the hit of camera
// ray origins[k].x (normals turned toward the camera, offset by eps along
// the geometric normal), cosine-distributed about its shading normal with
// the first two draws of stream origins[k].y under the bounce key; its
// closest hit comes back as the triangle.

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

struct BounceParams {
    count: u32,
    row: u32,
    key_lo: u32,
    key_hi: u32,
    eps: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read_write> hits: array<u32>;
@group(1) @binding(2) var<uniform> bp: BounceParams;
@group(1) @binding(3) var<storage, read> origins: array<vec2<u32>>;
@group(1) @binding(4) var<storage, read_write> bounce_hits: array<u32>;

// Camera ray j, as vpl_core::CameraRays::ray.
fn camera_ray(j: u32) -> CameraRay {
    return camera_ray_of(params.origin, params.forward, params.right, params.up, params.raster, vec2<u32>(params.key_lo, params.key_hi), j);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let j = id.x + id.y * params.row;
    if (j >= params.count) { return; }
    let ray = camera_ray(j);
    let hit = closest_hit(ray.o, ray.d, NO_HIT);
    var t = NO_HIT;
    var tri = NONE;
    if (hit.prim != NONE) {
        t = hit.t;
        tri = bvh_order[hit.prim];
    }
    write_hit(j, t, tri);
}

@compute @workgroup_size(64)
fn bounce(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x + id.y * bp.row;
    if (k >= bp.count) { return; }
    let org = origins[k];
    let tri = hits[org.x];
    if (tri == NONE) {
        bounce_hits[k] = NONE;
        return;
    }
    let ray = camera_ray(org.x);
    let p = ray.o + ray.d * bitcast<f32>(hits[params.count + org.x]);
    let sf = surface_of(tri, p);
    var n = sf.n;
    var ng = sf.ng;
    // SurfacePoint::facing(-d).
    if (dot(-ray.d, ng) < 0.0) {
        n = -n;
        ng = -ng;
    }
    seed_stream(org.y, vec2<u32>(bp.key_lo, bp.key_hi));
    let u = next_f32();
    let v = next_f32();
    let d = to_world(n, cosine_hemisphere(u, v));
    let h = closest_hit(p + ng * bp.eps, d, NO_HIT);
    if (h.prim == NONE) {
        bounce_hits[k] = NONE;
    } else {
        bounce_hits[k] = bvh_order[h.prim];
    }
}
