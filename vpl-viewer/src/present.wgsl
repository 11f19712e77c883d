// The view composed on the device: the twin of view::compose, pixel for
// pixel. Three passes over one bind group: the farthest surface seen (the
// depth channel's scale), the VPL splats (each pixel keeps the last VPL,
// in slot order, that covers it), and the composite itself, written as the
// sRGB bytes the host's compose writes.

struct Params {
    width: u32,
    height: u32,
    // Padded row of the output, in pixels.
    row: u32,
    // First column of the right side; 0xffffffff: not split.
    split_x: u32,
    channel: u32,
    overlay: u32,
    has_reference: u32,
    // Splat entries of the left side, then of the right.
    splats_left: u32,
    splats: u32,
    // The picked VPL's side (0xffffffff: none) and interleaving class (0xffffffff: none).
    pick_side: u32,
    pick_class: u32,
    // The side whose columns ring the picked VPL (0xffffffff: no ring).
    ring_side: u32,
    exposure: f32,
    ref_scale: f32,
    // Where the picked VPL falls, and its distance from the eye.
    ring_x: f32,
    ring_y: f32,
    ring_dist: f32,
    pad1: f32,
    pad2: f32,
    pad3: f32,
}

// A VPL as the overlay draws it: where it falls in the image, its distance
// from the eye, its colour (RGB bytes) and, in the top byte, whether it moved.
struct Splat {
    px: f32,
    py: f32,
    dist: f32,
    colour: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> image_l: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> image_r: array<vec4<f32>>;
// The G-buffer's shading normal (xyz) and depth (w; NO_HIT at a miss).
@group(0) @binding(3) var<storage, read> g_normal: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> g_albedo: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> reference: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> splats: array<Splat>;
// [0]: the farthest depth's bits; [1 + pixel]: 1 + the splat that covers it last.
@group(0) @binding(7) var<storage, read_write> scratch: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> out_px: array<u32>;

const NO_HIT: f32 = 3.0e38;
const NONE: u32 = 0xffffffffu;
const MARK: u32 = 0xffffffffu;
// Magenta, opaque.
const PICKED: u32 = 0xffff00ffu;

const OV_VPLS: u32 = 1u;
const OV_INTERLEAVE: u32 = 2u;

fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

fn reinhard(c: vec3<f32>) -> vec3<f32> {
    let l = luminance(c);
    if l <= 0.0 {
        return vec3<f32>(0.0);
    }
    return c / (1.0 + l);
}

fn srgb1(v0: f32) -> f32 {
    let v = max(v0, 0.0);
    if v <= 0.0031308 {
        return 12.92 * v;
    }
    return 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

fn to_srgb(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(srgb1(c.x), srgb1(c.y), srgb1(c.z));
}

fn byte(v: f32) -> u32 {
    return u32(clamp(v, 0.0, 1.0) * 255.0 + 0.5);
}

fn pack(c: vec3<f32>) -> u32 {
    return byte(c.x) | (byte(c.y) << 8u) | (byte(c.z) << 16u) | (255u << 24u);
}

fn unpack(p: u32) -> vec3<f32> {
    return vec3<f32>(f32(p & 255u), f32((p >> 8u) & 255u), f32((p >> 16u) & 255u)) / 255.0;
}

fn depth_at(i: u32) -> f32 {
    return g_normal[i].w;
}

// Whether a point at `dist` from the eye, falling at (px, py), is not
// behind the surface its pixel sees (the host's `seen`).
fn seen(px: f32, py: f32, dist: f32) -> bool {
    if !(px >= 0.0 && py >= 0.0 && px < f32(params.width) && py < f32(params.height)) {
        return false;
    }
    let surface = depth_at(u32(py) * params.width + u32(px));
    return dist <= surface * 1.02 + 1e-3 * max(surface, 1.0);
}

// The columns of side k: [x0, x1).
fn columns(k: u32) -> vec2<u32> {
    if params.split_x == NONE {
        // Unsplit, the right side has no columns.
        return select(vec2<u32>(params.width, params.width), vec2<u32>(0u, params.width), k == 0u);
    }
    if k == 0u {
        return vec2<u32>(0u, params.split_x);
    }
    return vec2<u32>(params.split_x, params.width);
}

fn class_hue(c: u32) -> vec3<f32> {
    let h = f32((c * 7u) % 16u) / 16.0 * 6.0;
    let x = 1.0 - abs(h % 2.0 - 1.0);
    switch u32(h) {
        case 0u: { return vec3<f32>(1.0, x, 0.0); }
        case 1u: { return vec3<f32>(x, 1.0, 0.0); }
        case 2u: { return vec3<f32>(0.0, 1.0, x); }
        case 3u: { return vec3<f32>(0.0, x, 1.0); }
        case 4u: { return vec3<f32>(x, 0.0, 1.0); }
        default: { return vec3<f32>(1.0, 0.0, x); }
    }
}

@compute @workgroup_size(8, 8)
fn far_pass(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let d = depth_at(id.y * params.width + id.x);
    if d < NO_HIT && d >= 0.0 {
        // Non-negative floats order as their bits do.
        atomicMax(&scratch[0], bitcast<u32>(d));
    }
}

fn cover(x: i32, y: i32, cols: vec2<u32>, key: u32) {
    if x >= i32(cols.x) && x < i32(cols.y) && y >= 0 && y < i32(params.height) {
        atomicMax(&scratch[1u + u32(y) * params.width + u32(x)], key);
    }
}

@compute @workgroup_size(64)
fn splat_pass(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= params.splats {
        return;
    }
    let s = splats[k];
    if !seen(s.px, s.py, s.dist) {
        return;
    }
    let cols = columns(select(0u, 1u, k >= params.splats_left));
    let x = i32(u32(s.px));
    let y = i32(u32(s.py));
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            cover(x + dx, y + dy, cols, k + 1u);
        }
    }
    if (s.colour >> 24u) != 0u {
        for (var d = -2; d <= 2; d++) {
            cover(x + d, y - 2, cols, k + 1u);
            cover(x + d, y + 2, cols, k + 1u);
            cover(x - 2, y + d, cols, k + 1u);
            cover(x + 2, y + d, cols, k + 1u);
        }
    }
}

// The channel's display value at pixel (x, y) of `side`: 0 image, 1
// reference, 2 difference, 3 albedo, 4 normals, 5 depth (view::Channel).
fn base(x: u32, y: u32, side: u32) -> u32 {
    let i = y * params.width + x;
    let exposure = params.exposure;
    switch params.channel {
        case 0u: {
            var c = image_l[i].xyz;
            if side == 1u {
                c = image_r[i].xyz;
            }
            return pack(to_srgb(reinhard(c * exposure)));
        }
        case 1u: {
            if params.has_reference == 0u {
                return pack(vec3<f32>(0.0));
            }
            return pack(to_srgb(reinhard(reference[i].xyz * exposure)));
        }
        case 2u: {
            if params.has_reference == 0u {
                return pack(vec3<f32>(0.0));
            }
            var c = image_l[i].xyz;
            if side == 1u {
                c = image_r[i].xyz;
            }
            let d = c - reference[i].xyz;
            let t = clamp(luminance(d) / params.ref_scale * exposure, -1.0, 1.0);
            var v = vec3<f32>(0.0, -0.15 * t, -t);
            if t >= 0.0 {
                v = vec3<f32>(t, 0.15 * t, 0.0);
            }
            return pack(to_srgb(v));
        }
        case 3u: {
            return pack(to_srgb(g_albedo[i].xyz));
        }
        case 4u: {
            let g = g_normal[i];
            if g.w >= NO_HIT || all(g.xyz == vec3<f32>(0.0)) {
                return pack(vec3<f32>(0.0));
            }
            return pack(g.xyz * 0.5 + 0.5);
        }
        default: {
            let d = depth_at(i);
            if d >= NO_HIT {
                return pack(vec3<f32>(0.0));
            }
            let far = max(bitcast<f32>(atomicLoad(&scratch[0])), 1e-6);
            return pack(vec3<f32>(1.0 - d / far));
        }
    }
}

@compute @workgroup_size(8, 8)
fn compose_pass(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let y = id.y;
    if x >= params.width || y >= params.height {
        return;
    }
    var side = 0u;
    if params.split_x != NONE && x >= params.split_x {
        side = 1u;
    }
    var px = base(x, y, side);
    if params.overlay == OV_VPLS {
        let w = atomicLoad(&scratch[1u + y * params.width + x]);
        if w > 0u {
            let s = splats[w - 1u];
            let sx = i32(u32(s.px));
            let sy = i32(u32(s.py));
            if abs(i32(x) - sx) <= 1 && abs(i32(y) - sy) <= 1 {
                px = (s.colour & 0x00ffffffu) | (255u << 24u);
            } else {
                px = MARK;
            }
        }
    } else if params.overlay == OV_INTERLEAVE {
        let c = (y % 4u) * 4u + x % 4u;
        let v = unpack(px);
        var o: vec3<f32>;
        if params.pick_side == side && params.pick_class != NONE {
            if params.pick_class == c {
                o = v + (vec3<f32>(1.0, 0.0, 1.0) - v) * 0.35;
            } else {
                o = v * 0.25;
            }
        } else {
            o = v + (to_srgb(class_hue(c)) - v) * 0.45;
        }
        px = pack(o);
    }
    // The picked VPL, ringed (9×9) within its side's columns.
    if params.ring_side != NONE && seen(params.ring_x, params.ring_y, params.ring_dist) {
        let cols = columns(params.ring_side);
        let cx = i32(u32(params.ring_x));
        let cy = i32(u32(params.ring_y));
        let dx = i32(x) - cx;
        let dy = i32(y) - cy;
        let on_ring = (abs(dx) <= 4 && abs(dy) == 4) || (abs(dy) <= 4 && abs(dx) == 4);
        if on_ring && x >= cols.x && x < cols.y {
            px = PICKED;
        }
    }
    if params.split_x != NONE && x + 1u >= params.split_x && x < params.split_x + 1u {
        px = MARK;
    }
    out_px[y * params.row + x] = px;
}
