// Reflected radiance from demodulated sums: L = E * (rho / pi), as the CPU
// shaders multiply after filtering.

struct Params {
    count: u32,
    row: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> e: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> albedo: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> radiance: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.count) { return; }
    radiance[i] = vec4<f32>(e[i].xyz * (albedo[i].xyz * 0.31830987), 0.0);
}
