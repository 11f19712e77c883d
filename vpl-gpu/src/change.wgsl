// Σ|b − a| and Σ max(b.r + b.g + b.b, 0) over the pixels of two images:
// each workgroup sums a stride of the pixels and writes one pair.

struct Params {
    count: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> previous: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> current: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> partial: array<vec2<f32>>;

const GROUP: u32 = 256u;
var<workgroup> sums: array<vec2<f32>, 256>;

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let stride = GROUP * groups.x;
    var acc = vec2<f32>(0.0);
    var i = wg.x * GROUP + li;
    loop {
        if i >= params.count {
            break;
        }
        let a = previous[i].xyz;
        let b = current[i].xyz;
        let d = abs(b - a);
        acc += vec2<f32>(d.x + d.y + d.z, max(b.x + b.y + b.z, 0.0));
        i += stride;
    }
    sums[li] = acc;
    workgroupBarrier();
    var s = GROUP / 2u;
    loop {
        if s == 0u {
            break;
        }
        if li < s {
            sums[li] += sums[li + s];
        }
        workgroupBarrier();
        s = s / 2u;
    }
    if li == 0u {
        partial[wg.x] = sums[0];
    }
}
