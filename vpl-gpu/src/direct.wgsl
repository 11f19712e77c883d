// ---- the frame's emission and direct light over a G-buffer ----
// Twin of vpl_shading::direct_light (and of the emission the host adds):
// per pixel that reflects, `samples` light samples stratified in u_sel,
// from stream(seed, 0, DIRECT, pixel); added to the image the gather left.

struct DirectParams {
    width: u32,
    height: u32,
    samples: u32,
    // 1: add the G-buffer's emission; 2: add the direct light.
    flags: u32,
    key: vec2<u32>,
    pad0: u32,
    pad1: u32,
}

@group(2) @binding(0) var<uniform> dparams: DirectParams;
@group(2) @binding(1) var<storage, read> d_pos: array<vec4<f32>>;
@group(2) @binding(2) var<storage, read> d_normal: array<vec4<f32>>;
@group(2) @binding(3) var<storage, read> d_ng: array<vec4<f32>>;
@group(2) @binding(4) var<storage, read> d_albedo: array<vec4<f32>>;
@group(2) @binding(5) var<storage, read> d_emitted: array<vec4<f32>>;
@group(2) @binding(6) var<storage, read_write> d_image: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn direct(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= dparams.width || id.y >= dparams.height) { return; }
    let i = id.y * dparams.width + id.x;
    var v = d_image[i].xyz;
    if ((dparams.flags & 1u) != 0u) {
        v = v + d_emitted[i].xyz;
    }
    let pos = d_pos[i];
    if ((dparams.flags & 2u) != 0u && pos.w > 0.0) {
        seed_stream(i, dparams.key);
        let n = d_normal[i].xyz;
        let ng = d_ng[i].xyz;
        let s = max(dparams.samples, 1u);
        var sum = vec3<f32>(0.0);
        for (var k = 0u; k < s; k = k + 1u) {
            let u_sel = (f32(k) + next_f32()) / f32(s);
            let u0 = next_f32();
            let u1 = next_f32();
            let ls = sample_light(pos.xyz, u_sel, u0, u1);
            if (!ls.ok) { continue; }
            let c = dot(n, ls.wi);
            if (c <= 0.0 || dot(ls.wi, ng) <= 0.0) { continue; }
            if (!light_unoccluded(pos.xyz, ng, ls)) { continue; }
            sum = sum + ls.li * (c / (ls.p_sel * ls.pdf));
        }
        v = v + d_albedo[i].xyz * FRAC_1_PI * sum / f32(s);
    }
    d_image[i] = vec4<f32>(v, 0.0);
}
