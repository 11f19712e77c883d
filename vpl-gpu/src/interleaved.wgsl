// Interleaved VPL gathering, twin of vpl_shading::InterleavedShader's sums:
// pixel (x, y) of class c = 4 (y mod 4) + (x mod 4) sums over the slots of
// subset c
//     E(x) = (I / n_c) sum_v flux_v min(G(x, v), G_max) V(x, v),
//     G = cos_y cos_x / |x - y|^2 (with unnormalised cosines: / d2^2),
// V from the paraboloid shadow maps (mode 0; the test and bias of
// vpl_visibility::MapView::visible) or shadow rays (mode 1; as
// vpl_visibility::RayTraced).

struct Params {
    width: u32,
    height: u32,
    // Slots I.
    slots: u32,
    // 0: shadow maps, 1: shadow rays.
    mode: u32,
    res: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    g_max: f32,
    // 2 eps (shadow-map bias floor).
    eps2: f32,
    // k * 2 / res (bias per unit distance and slope).
    texel: f32,
    // The scene's ray offset eps.
    eps: f32,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> g_pos: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> g_normal: array<vec4<f32>>;
// Three vec4 per slot: [y, 1 if the slot holds a VPL], [n_y, -], [flux, -].
@group(1) @binding(3) var<storage, read> vpls: array<vec4<f32>>;
// The slots of subset c: subset_slots[subset_offsets[c] .. subset_offsets[c + 1]].
@group(1) @binding(4) var<storage, read> subset_slots: array<u32>;
@group(1) @binding(5) var<storage, read> subset_offsets: array<u32>;
// Shadow maps (vpl_gpu::GpuShadowMaps): four vec4 per slot, [origin, has map], s, t, n;
// res * res depths per slot.
@group(1) @binding(6) var<storage, read> headers: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read> atlas: array<f32>;
@group(1) @binding(8) var<storage, read_write> out_e: array<vec4<f32>>;

// map_visible and ray_visible: vpl_visible.wgsl.

// Deinterleaved dispatch: z is the class c, (x, y) the 4x4 tile, so the
// invocations of a workgroup share a class and walk the same VPLs in step
// (uniform loads of the VPL, coherent reads of its shadow map).
@compute @workgroup_size(8, 8)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    let c = id.z;
    let x = id.x * 4u + c % 4u;
    let y = id.y * 4u + c / 4u;
    if (x >= params.width || y >= params.height) { return; }
    let i = y * params.width + x;
    let gp = g_pos[i];
    if (gp.w == 0.0) {
        out_e[i] = vec4<f32>(0.0);
        return;
    }
    let p = gp.xyz;
    let n = g_normal[i].xyz;
    let first = subset_offsets[c];
    let last = subset_offsets[c + 1u];
    var sum = vec3<f32>(0.0);
    for (var k = first; k < last; k = k + 1u) {
        let slot = subset_slots[k];
        let a = vpls[3u * slot];
        if (a.w == 0.0) { continue; }
        let n_y = vpls[3u * slot + 1u].xyz;
        let d = p - a.xyz;
        let d2 = dot(d, d);
        let cos_y = dot(n_y, d);
        let cos_x = -dot(n, d);
        if (!(cos_y > 0.0 && cos_x > 0.0 && d2 > 0.0)) { continue; }
        let g = min(cos_y * cos_x / (d2 * d2), params.g_max);
        var seen = false;
        if (params.mode == 0u) {
            seen = headers[4u * slot].w != 0.0 && map_visible(slot, p, n);
        } else {
            seen = ray_visible(a.xyz, n_y, p, n);
        }
        if (seen) {
            sum = sum + vpls[3u * slot + 2u].xyz * g;
        }
    }
    let count = last - first;
    var weight = 0.0;
    if (count > 0u) { weight = f32(params.slots) / f32(count); }
    out_e[i] = vec4<f32>(weight * sum, 0.0);
}
