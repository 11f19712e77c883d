// The cross-bilateral filter of vpl_shading::CrossBilateral, one invocation a pixel:
// w(p, q) = t(dx) t(dy) max(0, n_p . n_q)^alpha exp(-|x_p - x_q|^2 / 2 sigma_p^2),
// sigma_p = sigma * depth * pixel angle / max(|n . view|, 0.1).

struct Params {
    width: u32,
    height: u32,
    radius: i32,
    normal_power: u32,
    // xyz: the eye, w: the pixel angle.
    eye: vec4<f32>,
    sigma: f32,
    pad0: f32,
    pad1: f32,
    pad2: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
// The G-buffer (vpl_gpu::DeviceGBuffer): [p, reflects], [n, depth].
@group(0) @binding(1) var<storage, read> g_pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> g_normal: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> output: array<vec4<f32>>;

// x^k by squaring, as the CPU twin.
fn pow_u(x0: f32, k0: u32) -> f32 {
    var x = x0;
    var k = k0;
    var r = 1.0;
    loop {
        if (k == 0u) { break; }
        if ((k & 1u) == 1u) { r = r * x; }
        x = x * x;
        k = k >> 1u;
    }
    return r;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.width || id.y >= params.height) { return; }
    let w = i32(params.width);
    let h = i32(params.height);
    let x = i32(id.x);
    let y = i32(id.y);
    let i0 = u32(y * w + x);
    let p = g_pos[i0];
    if (p.w == 0.0) {
        output[i0] = vec4<f32>(0.0);
        return;
    }
    let gn = g_normal[i0];
    let np = gn.xyz;
    let to_eye = params.eye.xyz - p.xyz;
    let len2 = dot(to_eye, to_eye);
    var view = vec3<f32>(0.0);
    if (len2 > 0.0) { view = to_eye * inverseSqrt(len2); }
    let footprint = gn.w * params.eye.w / max(abs(dot(np, view)), 0.1);
    let s = params.sigma * footprint;
    let inv_2s2 = 1.0 / max(2.0 * (s * s), 1.1754944e-38);
    let r = params.radius;
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var qy = max(y - r, 0); qy <= min(y + r, h - 1); qy = qy + 1) {
        let ty = select(1.0, 0.5, abs(qy - y) == r);
        for (var qx = max(x - r, 0); qx <= min(x + r, w - 1); qx = qx + 1) {
            let i = u32(qy * w + qx);
            let q = g_pos[i];
            if (q.w == 0.0) { continue; }
            let tx = select(1.0, 0.5, abs(qx - x) == r);
            let wn = pow_u(max(dot(np, g_normal[i].xyz), 0.0), params.normal_power);
            let d = p.xyz - q.xyz;
            let wd = exp(-dot(d, d) * inv_2s2);
            let wt = tx * ty * wn * wd;
            sum = sum + input[i].xyz * wt;
            wsum = wsum + wt;
        }
    }
    if (wsum > 0.0) {
        output[i0] = vec4<f32>(sum / wsum, 0.0);
    } else {
        output[i0] = input[i0];
    }
}
