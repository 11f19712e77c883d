// Batch ray casting: one invocation a ray. Rays are `stride` floats each:
// origin, direction and, for a stride of 7, t_max (6: unbounded). Closest
// hits come back as hits.wgsl writes them; occlusion as one bit a ray
// (bit i % 32 of word i / 32), so an occlusion batch reads back n / 8 bytes.

struct Params {
    count: u32,
    row: u32,
    stride: u32,
    tri_only: u32,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> rays: array<f32>;
@group(1) @binding(2) var<storage, read_write> hits: array<u32>;
@group(1) @binding(3) var<storage, read_write> blocked: array<atomic<u32>>;

struct RayIn {
    o: vec3<f32>,
    d: vec3<f32>,
    t_max: f32,
}

fn ray_at(i: u32) -> RayIn {
    let k = params.stride * i;
    var t_max = NO_HIT;
    if (params.stride == 7u) { t_max = rays[k + 6u]; }
    return RayIn(vec3<f32>(rays[k], rays[k + 1u], rays[k + 2u]), vec3<f32>(rays[k + 3u], rays[k + 4u], rays[k + 5u]), t_max);
}

@compute @workgroup_size(64)
fn closest(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.count) { return; }
    let r = ray_at(i);
    let h = closest_hit(r.o, r.d, r.t_max);
    if (h.prim == NONE) {
        write_hit(i, NO_HIT, NONE);
    } else {
        write_hit(i, h.t, bvh_order[h.prim]);
    }
}

@compute @workgroup_size(64)
fn any_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.count) { return; }
    let r = ray_at(i);
    if (occluded(r.o, r.d, r.t_max)) {
        atomicOr(&blocked[i / 32u], 1u << (i % 32u));
    }
}
