// Batch ray casting: one invocation a ray. Rays are two vec4 each:
// [origin, t_max], [direction, -]. Closest hits come back as
// (t, scene triangle) pairs, occlusion as one bit a ray (bit i % 32 of
// word i / 32), so an occlusion batch reads back n / 8 bytes.

struct Params {
    count: u32,
    row: u32,
    pad0: u32,
    pad1: u32,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> rays: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read_write> hits: array<vec2<u32>>;
@group(1) @binding(3) var<storage, read_write> blocked: array<atomic<u32>>;

@compute @workgroup_size(64)
fn closest(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.count) { return; }
    let a = rays[2u * i];
    let b = rays[2u * i + 1u];
    let h = closest_hit(a.xyz, b.xyz, a.w);
    if (h.prim == NONE) {
        hits[i] = vec2<u32>(bitcast<u32>(NO_HIT), NONE);
    } else {
        hits[i] = vec2<u32>(bitcast<u32>(h.t), bvh_order[h.prim]);
    }
}

@compute @workgroup_size(64)
fn any_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.count) { return; }
    let a = rays[2u * i];
    let b = rays[2u * i + 1u];
    if (occluded(a.xyz, b.xyz, a.w)) {
        atomicOr(&blocked[i / 32u], 1u << (i % 32u));
    }
}
