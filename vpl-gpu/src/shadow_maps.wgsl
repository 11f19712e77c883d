// Paraboloid shadow maps by ray casting, twin of vpl_visibility::ShadowMaps:
// texel (i, j) of a map holds the distance to the first surface along the
// direction at paraboloid coordinates of its centre. One invocation a texel
// of one map; z indexes the maps to render.
//
// headers: four vec4 per slot: [origin, 1 if the slot holds a map], s, t, n.
// jobs: the slots to render. atlas: res * res floats per slot.

struct Params {
    res: u32,
    jobs: u32,
    pad0: u32,
    pad1: u32,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> headers: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> jobs: array<u32>;
@group(1) @binding(3) var<storage, read_write> atlas: array<f32>;

// The local direction at paraboloid coordinates uv; points outside the unit
// disk go to its rim (vpl_visibility::paraboloid_to_direction).
fn paraboloid_to_direction(uv0: vec2<f32>) -> vec3<f32> {
    let r2_0 = dot(uv0, uv0);
    var uv = uv0;
    if (r2_0 > 1.0) { uv = uv0 / sqrt(r2_0); }
    let r2 = min(r2_0, 1.0);
    return vec3<f32>(2.0 * uv.x, 2.0 * uv.y, 1.0 - r2) / (1.0 + r2);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let res = params.res;
    if (id.x >= res || id.y >= res || id.z >= params.jobs) { return; }
    let slot = jobs[id.z];
    let o = headers[4u * slot].xyz;
    let s = headers[4u * slot + 1u].xyz;
    let t = headers[4u * slot + 2u].xyz;
    let n = headers[4u * slot + 3u].xyz;
    let scale = 2.0 / f32(res);
    let u = (f32(id.x) + 0.5) * scale - 1.0;
    let v = (f32(id.y) + 0.5) * scale - 1.0;
    let l = paraboloid_to_direction(vec2<f32>(u, v));
    let d = s * l.x + t * l.y + n * l.z;
    let h = closest_hit(o, d, NO_HIT);
    atlas[slot * res * res + id.y * res + id.x] = h.t;
}
