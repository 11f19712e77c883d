// What kernels draw with: PCG32 on 32-bit words, the same streams as
// vpl_core::rng (keyed_state of a stream key and an index), and the
// samplings of vpl_core::sampling that need no more than that.

const FRAC_PI_4: f32 = 0.7853982;

// ---- PCG32 on 32-bit words ----

// The full 64-bit product of two 32-bit words as (lo, hi).
fn mul_wide(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2<u32>((p00 & 0xffffu) | (mid << 16u), p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

// a * b + c mod 2^64, each (lo, hi).
fn mul_add64(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>) -> vec2<u32> {
    let p = mul_wide(a.x, b.x);
    let hi = p.y + a.x * b.y + a.y * b.x;
    let lo = p.x + c.x;
    let carry = select(0u, 1u, lo < p.x);
    return vec2<u32>(lo, hi + c.y + carry);
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// a >> n for 0 < n < 32.
fn shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// SplitMix64's finaliser, vpl_core::rng::mix64.
fn mix64(v: vec2<u32>) -> vec2<u32> {
    let zero = vec2<u32>(0u);
    var z = add64(v, vec2<u32>(0x7F4A7C15u, 0x9E3779B9u));
    z = mul_add64(z ^ shr64(z, 30u), vec2<u32>(0x1CE4E5B9u, 0xBF58476Du), zero);
    z = mul_add64(z ^ shr64(z, 27u), vec2<u32>(0x133111EBu, 0x94D049BBu), zero);
    return z ^ shr64(z, 31u);
}

// vpl_core::rng::keyed_state: the PCG32 (state, increment) of stream
// `index` under `key`.
fn keyed_state(key: vec2<u32>, index: u32) -> vec4<u32> {
    return keyed_state64(key, vec2<u32>(index, 0u));
}

// keyed_state of a 64-bit index (lo, hi).
fn keyed_state64(key: vec2<u32>, index: vec2<u32>) -> vec4<u32> {
    let zero = vec2<u32>(0u);
    let state = mix64(key ^ index);
    // key.rotate_left(17)
    let rot = vec2<u32>((key.x << 17u) | (key.y >> 15u), (key.y << 17u) | (key.x >> 15u));
    let sequence = mix64(rot ^ mul_add64(index, vec2<u32>(0x7F4A7C15u, 0x9E3779B9u), zero));
    let inc = vec2<u32>((sequence.x << 1u) | 1u, (sequence.y << 1u) | (sequence.x >> 31u));
    let s = mul_add64(add64(state, inc), vec2<u32>(0x4C957F2Du, 0x5851F42Du), inc);
    return vec4<u32>(s, inc);
}

var<private> rng_state: vec2<u32>;
var<private> rng_inc: vec2<u32>;

// Starts this invocation's draws at stream `index` under `key`.
fn seed_stream(index: u32, key: vec2<u32>) {
    seed_stream64(vec2<u32>(index, 0u), key);
}

// seed_stream of a 64-bit index (lo, hi).
fn seed_stream64(index: vec2<u32>, key: vec2<u32>) {
    let r = keyed_state64(key, index);
    rng_state = r.xy;
    rng_inc = r.zw;
}

fn next_u32() -> u32 {
    let s = rng_state;
    // 6364136223846793005 = 0x5851F42D_4C957F2D
    rng_state = mul_add64(s, vec2<u32>(0x4C957F2Du, 0x5851F42Du), rng_inc);
    let rot = s.y >> 27u;
    // ((s >> 18) ^ s) >> 27, low 32 bits
    let t_lo = ((s.x >> 18u) | (s.y << 14u)) ^ s.x;
    let t_hi = (s.y >> 18u) ^ s.y;
    let xsh = (t_lo >> 27u) | (t_hi << 5u);
    return (xsh >> rot) | (xsh << ((32u - rot) & 31u));
}

fn next_f32() -> f32 {
    return f32(next_u32() >> 8u) * (1.0 / 16777216.0);
}

// ---- sampling (vpl_core::sampling) ----

// (cos x, sin x) for |x| <= pi/4 by Taylor polynomials (errors below
// 2e-9): the shading language's cos and sin may be off by 2^-11 (Vulkan's
// bound), enough to move a long ray across an edge.
fn cos_sin(x: f32) -> vec2<f32> {
    let x2 = x * x;
    let c = 1.0 + x2 * (-1.0 / 2.0 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0 + x2 * (-1.0 / 3628800.0)))));
    let s = x * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362880.0)))));
    return vec2<f32>(c, s);
}

// Shirley-Chiu concentric mapping (vpl_core::sampling::concentric_disk);
// cos(pi/2 - t) = sin t keeps every angle within pi/4.
fn concentric_disk(u: f32, v: f32) -> vec2<f32> {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if (a == 0.0 && b == 0.0) { return vec2<f32>(0.0); }
    if (abs(a) > abs(b)) {
        let cs = cos_sin(FRAC_PI_4 * (b / a));
        return vec2<f32>(a * cs.x, a * cs.y);
    }
    let cs = cos_sin(FRAC_PI_4 * (a / b));
    return vec2<f32>(b * cs.y, b * cs.x);
}

fn cosine_hemisphere(u: f32, v: f32) -> vec3<f32> {
    let d = concentric_disk(u, v);
    return vec3<f32>(d.x, d.y, sqrt(max(1.0 - d.x * d.x - d.y * d.y, 0.0)));
}

// vpl_core::LocalFrame::from_normal(n).to_world(v)
fn to_world(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    // copysign(1, n.z): -0.0 counts as negative, as on the CPU.
    let sgn = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    let s = vec3<f32>(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    let t = vec3<f32>(b, sgn + n.y * n.y * a, -n.y);
    return s * v.x + t * v.y + n * v.z;
}

// ---- camera rays (vpl_core::CameraRays::ray) ----

struct CameraRay {
    o: vec3<f32>,
    d: vec3<f32>,
}

// Ray j of a batch under `key`: (u, v) and then the lens sample from stream
// j, through raster (u·w, v·h). The camera as four rows: the origin; the
// forward axis with s_x in w; the right axis with s_y; the true up with the
// focus distance; and the raster (width, height, lens radius (0: a pinhole), -).
// Leaves the stream after the ray's four draws.
fn camera_ray_of(origin: vec4<f32>, forward: vec4<f32>, right: vec4<f32>, up: vec4<f32>, raster: vec4<f32>, key: vec2<u32>, j: u32) -> CameraRay {
    seed_stream(j, key);
    let w = raster.x;
    let h = raster.y;
    let u = next_f32();
    let v = next_f32();
    let lu = next_f32();
    let lv = next_f32();
    return camera_ray_at(origin, forward, right, up, raster, u * w, v * h, lu, lv);
}

// The camera's ray through raster point (px, py) with lens sample (lu, lv)
// (vpl_core::Camera::ray), the camera in the rows of camera_ray_of.
fn camera_ray_at(origin: vec4<f32>, forward: vec4<f32>, right: vec4<f32>, up: vec4<f32>, raster: vec4<f32>, px: f32, py: f32, lu: f32, lv: f32) -> CameraRay {
    let w = raster.x;
    let h = raster.y;
    let ndc_x = 2.0 * px / w - 1.0;
    let ndc_y = 1.0 - 2.0 * py / h;
    let d = forward.xyz + right.xyz * (ndc_x * forward.w) + up.xyz * (ndc_y * right.w);
    var o = origin.xyz;
    var dir = normalize(d);
    if (raster.z > 0.0) {
        // Thin lens: from a point of the aperture toward the point in focus.
        let focus = o + d * up.w;
        let l = concentric_disk(lu, lv) * raster.z;
        o = o + right.xyz * l.x + up.xyz * l.y;
        dir = normalize(focus - o);
    }
    return CameraRay(o, dir);
}
