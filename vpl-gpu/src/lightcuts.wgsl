// Stochastic lightcuts, twin of vpl_shading::LightcutShader: per pixel the
// cut of vpl_lighttree::LightTree::cut (the node of largest importance split
// until N are held, ties to the earlier entry, removals by swap_remove),
// then one VPL below each cut node walked down by importance
// (LightTree::sample_below) with the same PCG32 stream (seed, frame,
// LIGHTCUT, pixel), and
//     E(x) = sum_cut flux_y min(G(x, y), G_max) V(x, y) / p_y,
// visibility as the interleaved gather tests it (vpl_visible.wgsl).

struct Params {
    width: u32,
    height: u32,
    // Slots I.
    slots: u32,
    // 0: shadow maps, 1: shadow rays.
    mode: u32,
    res: u32,
    // N: cut nodes a pixel (at most MAX_CUT).
    cut: u32,
    // Inner nodes of the tree; the bounds of slot s are entry nodes + s.
    nodes: u32,
    // The root as a packed child (SLOT bit for a slot); NONE: no light.
    root: u32,
    g_max: f32,
    eps2: f32,
    texel: f32,
    eps: f32,
    // The stream key of (seed, frame, LIGHTCUT).
    key: vec2<u32>,
    pad0: u32,
    pad1: u32,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> g_pos: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> g_normal: array<vec4<f32>>;
// Three vec4 per slot: [y, 1 if the slot holds a VPL], [n_y, -], [flux, -].
@group(1) @binding(3) var<storage, read> vpls: array<vec4<f32>>;
// Three vec4 per entry (inner nodes, then slots): [lo, power], [hi, cos_theta], [axis, -].
@group(1) @binding(4) var<storage, read> bounds: array<vec4<f32>>;
// Two packed children per inner node.
@group(1) @binding(5) var<storage, read> children: array<u32>;
@group(1) @binding(6) var<storage, read> headers: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read> atlas: array<f32>;
@group(1) @binding(8) var<storage, read_write> out_e: array<vec4<f32>>;

const SLOT: u32 = 0x80000000u;
// NONE (0xffffffff): bvh.wgsl's.
const MAX_CUT: u32 = 256u;
const SLACK: f32 = 1e-4;

var<private> cut_c: array<u32, 257>;
var<private> cut_w: array<f32, 257>;

fn entry(c: u32) -> u32 {
    if ((c & SLOT) != 0u) { return params.nodes + (c & ~SLOT); }
    return c;
}

fn sin_of(c: f32) -> f32 {
    return sqrt(max(1.0 - c * c, 0.0));
}

// cos(max(0, a - b)) and sin(max(0, a - b)) from sines and cosines.
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if (cos_a > cos_b) { return 1.0; }
    return cos_a * cos_b + sin_a * sin_b;
}

fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if (cos_a > cos_b) { return 0.0; }
    return sin_a * cos_b - cos_a * sin_b;
}

// vpl_shading's node_importance: pbrt-v4's LightBounds::Importance for
// cosine emitters, one-sided at the receiver x with normal n.
fn importance(c: u32, x: vec3<f32>, n: vec3<f32>) -> f32 {
    let e = 3u * entry(c);
    let a = bounds[e];
    let b = bounds[e + 1u];
    let axis = bounds[e + 2u].xyz;
    let power = a.w;
    let cos_theta = b.w;
    if (!(power > 0.0) || cos_theta > 1.0) { return 0.0; }
    let lo = a.xyz;
    let hi = b.xyz;
    let centre = (lo + hi) * 0.5;
    let diag = hi - lo;
    let r2 = dot(diag, diag) * 0.25;
    let to = centre - x;
    let dist2 = dot(to, to);
    var cos_b = -1.0;
    if (dist2 > r2) { cos_b = sqrt(max(1.0 - r2 / dist2, 0.0)); }
    let sin_b = sin_of(cos_b);
    let d2 = max(max(dist2, r2), 1e-12);
    var dir = vec3<f32>(0.0);
    if (dist2 > 0.0) { dir = to / sqrt(dist2); }
    let cos_w = clamp(dot(axis, -dir), -1.0, 1.0);
    let cos_o = clamp(cos_theta, -1.0, 1.0);
    let cos_x = cos_sub_clamped(sin_of(cos_w), cos_w, sin_of(cos_o), cos_o);
    let sin_x = sin_sub_clamped(sin_of(cos_w), cos_w, sin_of(cos_o), cos_o);
    let cos_light = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if (cos_light <= -SLACK) { return 0.0; }
    let cos_i = clamp(dot(n, dir), -1.0, 1.0);
    let cos_receiver = cos_sub_clamped(sin_of(cos_i), cos_i, sin_b, cos_b);
    if (cos_receiver <= -SLACK) { return 0.0; }
    return power * max(cos_light, SLACK) * max(cos_receiver, SLACK) / d2;
}

@compute @workgroup_size(8, 8)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.width || id.y >= params.height) { return; }
    let i = id.y * params.width + id.x;
    let gp = g_pos[i];
    if (gp.w == 0.0 || params.root == NONE) {
        out_e[i] = vec4<f32>(0.0);
        return;
    }
    let x = gp.xyz;
    let n = g_normal[i].xyz;
    // The cut (LightTree::cut).
    var len = 0u;
    let r = importance(params.root, x, n);
    if (r > 0.0) {
        cut_c[0] = params.root;
        cut_w[0] = r;
        len = 1u;
    }
    loop {
        if (len >= params.cut) { break; }
        var best = NONE;
        for (var k = 0u; k < len; k = k + 1u) {
            if ((cut_c[k] & SLOT) == 0u && (best == NONE || cut_w[k] > cut_w[best])) { best = k; }
        }
        if (best == NONE) { break; }
        let node = cut_c[best];
        // swap_remove
        len = len - 1u;
        cut_c[best] = cut_c[len];
        cut_w[best] = cut_w[len];
        for (var j = 0u; j < 2u; j = j + 1u) {
            let c = children[2u * node + j];
            let w = importance(c, x, n);
            if (w > 0.0) {
                cut_c[len] = c;
                cut_w[len] = w;
                len = len + 1u;
            }
        }
    }
    seed_stream(i, params.key);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < len; k = k + 1u) {
        // One light below the node (LightTree::sample_below).
        var at = cut_c[k];
        var p = 1.0;
        var ok = true;
        loop {
            if ((at & SLOT) != 0u) { break; }
            let a = children[2u * at];
            let b = children[2u * at + 1u];
            let ia = importance(a, x, n);
            let ib = importance(b, x, n);
            let total = ia + ib;
            // total is NaN, not positive, or infinite: the walk stops.
            if (!(total > 0.0) || total > 3.4028235e38) {
                ok = false;
                break;
            }
            let pa = ia / total;
            if (next_f32() < pa) {
                at = a;
                p = p * pa;
            } else {
                at = b;
                p = p * (1.0 - pa);
            }
        }
        if (!ok || !(p > 0.0)) { continue; }
        let slot = at & ~SLOT;
        if (slot >= params.slots) { continue; }
        let v = vpls[3u * slot];
        if (v.w == 0.0) { continue; }
        let n_y = vpls[3u * slot + 1u].xyz;
        let d = x - v.xyz;
        let d2 = dot(d, d);
        let cos_y = dot(n_y, d);
        let cos_x = -dot(n, d);
        if (!(cos_y > 0.0 && cos_x > 0.0 && d2 > 0.0)) { continue; }
        let g = min(cos_y * cos_x / (d2 * d2), params.g_max);
        if (!(g > 0.0)) { continue; }
        var seen = false;
        if (params.mode == 0u) {
            seen = headers[4u * slot].w != 0.0 && map_visible(slot, x, n);
        } else {
            seen = ray_visible(v.xyz, n_y, x, n);
        }
        if (seen) {
            sum = sum + vpls[3u * slot + 2u].xyz * (g / p);
        }
    }
    out_e[i] = vec4<f32>(sum, 0.0);
}
