// Algorithm 1 of Hedman et al. (2017) on the device, one iteration a
// submission: twin of vpl_smc::SmcSampler with the paper's kNN flux
// (eq. 5 with the densities of eqs. 7 and 8). Prepended: sampling.wgsl and
// bvh.wgsl (group 0, the scene). Every array is fixed-size and marks what
// it holds, so no count crosses to the host:
//
// pts (vec4): camera points X by camera ray, [xp | xn | xng] (xp.w = 1 where
//   the ray found a reflecting point); candidate-ray hits by camera ray,
//   [hp | hn | hng] (hp.w = 1 for a hit, hn.w its material, hng.w the camera
//   ray it left); the candidates' points [qp] (w = 1 for a candidate).
// particles (vec4, one row a slot in each part): [p (w: occupied) | n (w:
//   material) | ng | L (w: density p(y)) | selection L (w: intensity I(y)) |
//   anchor p | anchor n | anchor ng | id (x, y) and validity (z)].
// u32s: the compacted camera points (by ray), the resampling draws, the
//   candidates (hit indices, in draw order), the slots filled, the sort's
//   scratch, the taken marks.
// f32s: the hit weights and then their running sums (the CDF), the
//   candidates' intensities.
// state (atomics): counters and stats, at S_*.
// out: one VPL a slot (y and id lo, n and id hi, flux and occupied), then
//   the stats.

struct It {
    n: u32,
    c: u32,
    cs: u32,
    ns: u32,
    tries: u32,
    vis_rays: u32,
    vis_iters: u32,
    m_max: u32,
    row_c: u32,
    row_n: u32,
    np2: u32,
    two_sided: u32,
    paths: u32,
    // `row` of the draws' dispatch.
    row_d: u32,
    // Eq. 8's k.
    k: u32,
    pad1: u32,
    eps: f32,
    quantile: f32,
    area: f32,
    pad2: f32,
    key_cam: vec2<u32>,
    key_cand: vec2<u32>,
    key_res: vec2<u32>,
    key_vis: vec2<u32>,
    seed: vec2<u32>,
    purpose_radiosity: vec2<u32>,
    origin: vec4<f32>,
    // xyz and, in w: s_x (forward), s_y (right), focus distance (up).
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // Width, height, lens radius (0: a pinhole), -.
    raster: vec4<f32>,
}

@group(1) @binding(0) var<uniform> it: It;
@group(1) @binding(1) var<storage, read_write> state: array<atomic<u32>, 32>;
@group(1) @binding(2) var<storage, read_write> u32s: array<u32>;
@group(1) @binding(3) var<storage, read_write> pts: array<vec4<f32>>;
@group(1) @binding(4) var<storage, read_write> f32s: array<f32>;
@group(1) @binding(5) var<storage, read_write> particles: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read_write> out: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read_write> rjobs: array<vec4<f32>>;
@group(1) @binding(8) var<storage, read_write> rkeys: array<vec2<u32>>;
@group(1) @binding(9) var<storage, read> rsum: array<vec4<f32>>;
@group(1) @binding(10) var<storage, read> answers: array<vec4<u32>>;

// state
const S_NX: u32 = 0u;
const S_M: u32 = 1u;
const S_OCCUPIED: u32 = 2u;
const S_ID_LO: u32 = 3u;
const S_ID_HI: u32 = 4u;
const S_HITS: u32 = 5u;
const S_MAILBOX: u32 = 6u;
const S_RAY_VALID: u32 = 7u;
const S_INVALID: u32 = 8u;
const S_STRONG: u32 = 9u;
const S_WEAKEST: u32 = 10u;
const S_REMOVED: u32 = 11u;
const S_ADDED: u32 = 12u;
const S_STORED: u32 = 13u;
const S_CV: u32 = 14u;
// Set when a search came back with fewer neighbours than it must have:
// the device cut its loops short.
const S_CUT: u32 = 15u;
// Indirect dispatch sizes of the new VPLs' radiosity: paths, then sums.
const S_PATHS_GROUPS: u32 = 16u;
const S_SUM_GROUPS: u32 = 20u;

const PI: f32 = 3.14159265;

// ---- regions ----

fn xp(j: u32) -> u32 { return j; }
fn xn(j: u32) -> u32 { return it.cs + j; }
fn xng(j: u32) -> u32 { return 2u * it.cs + j; }
fn hp(j: u32) -> u32 { return 3u * it.cs + j; }
fn hn(j: u32) -> u32 { return 4u * it.cs + j; }
fn hng(j: u32) -> u32 { return 5u * it.cs + j; }
fn qp(i: u32) -> u32 { return 6u * it.cs + i; }

fn pp(s: u32) -> u32 { return s; }
fn pn(s: u32) -> u32 { return it.ns + s; }
fn png(s: u32) -> u32 { return 2u * it.ns + s; }
fn pl(s: u32) -> u32 { return 3u * it.ns + s; }
fn psel(s: u32) -> u32 { return 4u * it.ns + s; }
fn pap(s: u32) -> u32 { return 5u * it.ns + s; }
fn pan(s: u32) -> u32 { return 6u * it.ns + s; }
fn pang(s: u32) -> u32 { return 7u * it.ns + s; }
fn pid(s: u32) -> u32 { return 8u * it.ns + s; }

fn u_xlist(j: u32) -> u32 { return j; }
fn u_draw(d: u32) -> u32 { return it.c + d; }
fn u_cand(i: u32) -> u32 { return it.c + it.n * it.tries + i; }
fn u_added(i: u32) -> u32 { return it.c + it.n * (it.tries + 1u) + i; }
fn u_sort(i: u32) -> u32 { return it.c + it.n * (it.tries + 2u) + i; }
fn u_mark(j: u32) -> u32 { return it.c + it.n * (it.tries + 2u) + it.np2 + j; }

fn f_cdf(j: u32) -> u32 { return j; }
fn f_cand(i: u32) -> u32 { return it.c + i; }

fn occupied(s: u32) -> bool { return particles[pp(s)].w != 0.0; }

fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn lum(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

// I = L / p by luminance, 0 where not finite (vpl_smc's intensity).
fn intensity_of(l: vec3<f32>, p: f32) -> f32 {
    let v = lum(l) / p;
    if (!finite(v)) { return 0.0; }
    return max(v, 0.0);
}

// RngStream::below: Lemire's multiply-shift.
fn below(n: u32) -> u32 {
    return mul_wide(next_u32(), n).y;
}

// Scene::shadow_ray(a, b) is unblocked (coinciding points see each other).
fn visible(a: vec3<f32>, b: vec3<f32>) -> bool {
    let d = b - a;
    let len = length(d);
    if (len <= 0.0) { return true; }
    return !occluded(a, d / len, len * (1.0 - 1e-4) - it.eps);
}

// The reflecting surface a ray (o, d) meets: the point with normals turned
// toward the ray (Scene::reflecting); w of the first row 0 when none.
struct Reflecting {
    ok: bool,
    p: vec3<f32>,
    n: vec3<f32>,
    ng: vec3<f32>,
    material: u32,
}

fn reflecting(o: vec3<f32>, d: vec3<f32>) -> Reflecting {
    var r = Reflecting(false, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0u);
    let h = closest_hit(o, d, NO_HIT);
    if (h.prim == NONE) { return r; }
    let p = o + d * h.t;
    let sf = surface_at(h.prim, p);
    let wo = -d;
    if (dot(wo, sf.ng) <= 0.0 && it.two_sided == 0u) { return r; }
    var n = sf.n;
    var ng = sf.ng;
    if (dot(wo, ng) < 0.0) {
        n = -n;
        ng = -ng;
    }
    let rho = materials[2u * sf.material].xyz;
    if (max(max(rho.x, rho.y), rho.z) <= 0.0) { return r; }
    return Reflecting(true, p, n, ng, sf.material);
}

// ---- line 3: camera points X ----

@compute @workgroup_size(64)
fn camera_points(@builtin(global_invocation_id) id: vec3<u32>) {
    let j = id.x + id.y * it.row_c;
    if (j >= it.c) { return; }
    let ray = camera_ray_of(it.origin, it.forward, it.right, it.up, it.raster, it.key_cam, j);
    let r = reflecting(ray.o, ray.d);
    pts[xp(j)] = vec4<f32>(r.p, select(0.0, 1.0, r.ok));
    pts[xn(j)] = vec4<f32>(r.n, 0.0);
    pts[xng(j)] = vec4<f32>(r.ng, 0.0);
    // This iteration's hits and candidates are not made yet.
    pts[hp(j)] = vec4<f32>(0.0);
    if (j < it.n) { pts[qp(j)] = vec4<f32>(0.0); }
}

var<workgroup> wg_u: array<u32, 256>;

// Exclusive scan of wg_u over the workgroup; returns the total.
fn scan_wg(li: u32) -> u32 {
    for (var off = 1u; off < 256u; off = off * 2u) {
        var add = 0u;
        if (li >= off) { add = wg_u[li - off]; }
        workgroupBarrier();
        wg_u[li] = wg_u[li] + add;
        workgroupBarrier();
    }
    let total = wg_u[255];
    var before = 0u;
    if (li > 0u) { before = wg_u[li - 1u]; }
    workgroupBarrier();
    wg_u[li] = before;
    workgroupBarrier();
    return total;
}

// X compacted in ray order (the CPU's list), and its size.
@compute @workgroup_size(256)
fn compact_x(@builtin(local_invocation_index) li: u32) {
    let per = (it.c + 255u) / 256u;
    let a = min(li * per, it.c);
    let b = min(a + per, it.c);
    var count = 0u;
    for (var j = a; j < b; j = j + 1u) {
        if (pts[xp(j)].w != 0.0) { count = count + 1u; }
    }
    wg_u[li] = count;
    workgroupBarrier();
    let total = scan_wg(li);
    var at = wg_u[li];
    for (var j = a; j < b; j = j + 1u) {
        if (pts[xp(j)].w != 0.0) {
            u32s[u_xlist(at)] = j;
            at = at + 1u;
        }
    }
    if (li == 0u) {
        atomicStore(&state[S_NX], total);
        // This iteration's counters.
        for (var k = S_M; k < 16u; k = k + 1u) {
            if (k != S_ID_LO && k != S_ID_HI) { atomicStore(&state[k], 0u); }
        }
    }
}

// ---- line 4: indirect visibility by mailboxing (§3.2.2) ----

// vpl_smc::mutual_ray: whether camera point (x, xn, xng) and a VPL at y
// with normal n_y see each other with both cosines positive.
fn mutually_visible(x: vec3<f32>, x_n: vec3<f32>, x_ng: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> bool {
    let d = y - x;
    if (dot(d, x_ng) <= 0.0 || dot(d, x_n) <= 0.0 || dot(d, n_y) >= 0.0) { return false; }
    return visible(x + x_ng * it.eps, y + n_y * it.eps);
}

@compute @workgroup_size(64)
fn visibility(@builtin(global_invocation_id) id: vec3<u32>) {
    let s = id.x + id.y * it.row_n;
    if (s >= it.n || !occupied(s)) { return; }
    atomicAdd(&state[S_OCCUPIED], 1u);
    let anchor = particles[pap(s)].xyz;
    let a_ng = particles[pang(s)].xyz;
    // The mailbox: the camera still sees the anchor from its side, inside the image.
    var valid = 0u;
    let cam = it.origin.xyz;
    let v = anchor - cam;
    let z = dot(v, it.forward.xyz);
    if (dot(cam - anchor, a_ng) > 0.0 && z > 0.0) {
        let px = (dot(v, it.right.xyz) / (z * it.forward.w) + 1.0) * 0.5 * it.raster.x;
        let py = (1.0 - dot(v, it.up.xyz) / (z * it.right.w)) * 0.5 * it.raster.y;
        if (px >= 0.0 && px < it.raster.x && py >= 0.0 && py < it.raster.y && visible(anchor + a_ng * it.eps, cam)) {
            valid = 1u;
        }
    }
    let nx = atomicLoad(&state[S_NX]);
    if (valid == 0u && nx > 0u) {
        let y = particles[pp(s)].xyz;
        let n_y = particles[pn(s)].xyz;
        for (var round = 0u; round < it.vis_iters && valid == 0u; round = round + 1u) {
            seed_stream((s << 8u) | round, it.key_vis);
            for (var r = 0u; r < it.vis_rays; r = r + 1u) {
                let j = u32s[u_xlist(below(nx))];
                let x = pts[xp(j)].xyz;
                let x_n = pts[xn(j)].xyz;
                let x_ng = pts[xng(j)].xyz;
                if (mutually_visible(x, x_n, x_ng, y, n_y)) {
                    particles[pap(s)] = vec4<f32>(x, 0.0);
                    particles[pan(s)] = vec4<f32>(x_n, 0.0);
                    particles[pang(s)] = vec4<f32>(x_ng, 0.0);
                    valid = 2u;
                    break;
                }
            }
        }
    }
    var idv = particles[pid(s)];
    idv.z = f32(valid);
    particles[pid(s)] = idv;
    if (valid == 1u) { atomicAdd(&state[S_MAILBOX], 1u); }
    if (valid == 2u) { atomicAdd(&state[S_RAY_VALID], 1u); }
    if (valid == 0u) { atomicAdd(&state[S_INVALID], 1u); }
}

// ---- line 5: candidate rays from X ----

// Camera point i of X (in ray order, as the CPU numbers them) casts from
// stream i; its hit is kept at its camera ray's index j, which keeps the
// CPU's order of the hits.
@compute @workgroup_size(64)
fn candidate_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * it.row_c;
    if (i >= atomicLoad(&state[S_NX])) { return; }
    let j = u32s[u_xlist(i)];
    let x = pts[xp(j)].xyz;
    let n = pts[xn(j)].xyz;
    let ng = pts[xng(j)].xyz;
    seed_stream(i, it.key_cand);
    let u = next_f32();
    let v = next_f32();
    let d = to_world(n, cosine_hemisphere(u, v));
    if (dot(d, ng) <= 0.0) { return; }
    let r = reflecting(x + ng * it.eps, d);
    if (!r.ok) { return; }
    pts[hp(j)] = vec4<f32>(r.p, 1.0);
    pts[hn(j)] = vec4<f32>(r.n, bitcast<f32>(r.material));
    pts[hng(j)] = vec4<f32>(r.ng, bitcast<f32>(j));
    atomicAdd(&state[S_HITS], 1u);
}

// ---- line 6: weights 1/p_hit ∝ r_1², their running sums, the draws ----

@compute @workgroup_size(64)
fn weights(@builtin(global_invocation_id) id: vec3<u32>) {
    let j = id.x + id.y * it.row_c;
    if (j >= it.c) { return; }
    var w = 0.0;
    if (pts[hp(j)].w != 0.0) {
        if (atomicLoad(&state[S_HITS]) == 1u) {
            w = 1.0;
        } else if (answers[j].y != NONE) {
            w = bitcast<f32>(answers[j].z);
        } else {
            atomicStore(&state[S_CUT], 1u);
        }
    }
    if (!finite(w) || w < 0.0) { w = 0.0; }
    f32s[f_cdf(j)] = w;
}

var<workgroup> wg_f: array<f32, 256>;

// Inclusive running sums of the weights in place: each thread sums its run,
// the workgroup scans the runs' totals.
@compute @workgroup_size(256)
fn scan_weights(@builtin(local_invocation_index) li: u32) {
    let per = (it.c + 255u) / 256u;
    let a = min(li * per, it.c);
    let b = min(a + per, it.c);
    var sum = 0.0;
    for (var j = a; j < b; j = j + 1u) {
        sum = sum + f32s[f_cdf(j)];
        f32s[f_cdf(j)] = sum;
    }
    wg_f[li] = sum;
    workgroupBarrier();
    for (var off = 1u; off < 256u; off = off * 2u) {
        var add = 0.0;
        if (li >= off) { add = wg_f[li - off]; }
        workgroupBarrier();
        wg_f[li] = wg_f[li] + add;
        workgroupBarrier();
    }
    var before = 0.0;
    if (li > 0u) { before = wg_f[li - 1u]; }
    for (var j = a; j < b; j = j + 1u) {
        f32s[f_cdf(j)] = f32s[f_cdf(j)] + before;
    }
}

// Draw d's attempt a (vpl_core::resample_counted): the first hit whose
// running sum exceeds u · total, u from draw d's stream; uniform over the
// rays when no weight is positive (a ray without a hit then draws nothing).
@compute @workgroup_size(64)
fn draw(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x + id.y * it.row_d;
    if (k >= it.n * it.tries) { return; }
    let d = k / it.tries;
    let a = k % it.tries;
    seed_stream(d, it.key_res);
    let total = f32s[f_cdf(it.c - 1u)];
    var i = NONE;
    if (total > 0.0) {
        for (var s = 0u; s < a; s = s + 1u) {
            _ = next_u32();
            _ = next_u32();
        }
        let hi = next_u32();
        let lo = next_u32();
        let u = (f32(hi >> 8u) + f32(lo >> 8u) * (1.0 / 16777216.0)) * (1.0 / 16777216.0) * total;
        // The first running sum above u.
        var l = 0u;
        var r = it.c;
        loop {
            if (l >= r) { break; }
            let m = (l + r) / 2u;
            if (f32s[f_cdf(m)] <= u) { l = m + 1u; } else { r = m; }
        }
        i = min(l, it.c - 1u);
    } else {
        for (var s = 0u; s < a; s = s + 1u) {
            _ = next_u32();
        }
        i = below(it.c);
    }
    if (pts[hp(i)].w == 0.0) { i = NONE; }
    u32s[u_draw(k)] = i;
}

// One invocation: the draws in order, each taking its first attempt that
// lands on a hit not yet taken (without replacement, at most `tries`
// attempts); the candidates in draw order.
@compute @workgroup_size(1)
fn take() {
    let hits = atomicLoad(&state[S_HITS]);
    let draws = min(it.n, hits);
    var m = 0u;
    for (var d = 0u; d < draws; d = d + 1u) {
        for (var a = 0u; a < it.tries; a = a + 1u) {
            let i = u32s[u_draw(d * it.tries + a)];
            if (i == NONE || u32s[u_mark(i)] != 0u) { continue; }
            u32s[u_mark(i)] = 1u;
            u32s[u_cand(m)] = i;
            m = m + 1u;
            break;
        }
    }
    for (var c = 0u; c < m; c = c + 1u) {
        u32s[u_mark(u32s[u_cand(c)])] = 0u;
    }
    atomicStore(&state[S_M], m);
}

// ---- line 7: the candidates' radiosity jobs ----

// vpl_core::rng::stream_key(s, 0, RADIOSITY).
fn radiosity_key(s: vec2<u32>) -> vec2<u32> {
    return mix64(mix64(mix64(s)) ^ it.purpose_radiosity);
}

fn id_of(i: u32) -> vec2<u32> {
    return add64(vec2<u32>(atomicLoad(&state[S_ID_LO]), atomicLoad(&state[S_ID_HI])), vec2<u32>(i, 0u));
}

// SmcSampler::radiosity_seed: mix64(seed ^ mix64(id + 0x5EC0_0001)).
fn selection_seed(id: vec2<u32>) -> vec2<u32> {
    return mix64(it.seed ^ mix64(add64(id, vec2<u32>(0x5EC00001u, 0u))));
}

// SmcSampler::render_seed: mix64(seed ^ mix64(id + 0x5EC0_0002).rotate_left(17)).
fn render_seed(id: vec2<u32>) -> vec2<u32> {
    let m = mix64(add64(id, vec2<u32>(0x5EC00002u, 0u)));
    let rot = vec2<u32>((m.x << 17u) | (m.y >> 15u), (m.y << 17u) | (m.x >> 15u));
    return mix64(it.seed ^ rot);
}

fn job(k: u32, p: vec3<f32>, material: u32, n: vec3<f32>, ng: vec3<f32>, key: vec2<u32>) {
    rjobs[3u * k] = vec4<f32>(p, bitcast<f32>(material));
    rjobs[3u * k + 1u] = vec4<f32>(n, 0.0);
    rjobs[3u * k + 2u] = vec4<f32>(ng, 0.0);
    rkeys[k] = key;
}

@compute @workgroup_size(64)
fn candidate_jobs(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * it.row_n;
    if (i >= it.n) { return; }
    let m = atomicLoad(&state[S_M]);
    if (i >= m) {
        pts[qp(i)] = vec4<f32>(0.0);
        job(i, vec3<f32>(0.0), 0u, vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 0.0, 1.0), vec2<u32>(0u));
        return;
    }
    let h = u32s[u_cand(i)];
    let p = pts[hp(h)].xyz;
    pts[qp(i)] = vec4<f32>(p, 1.0);
    job(i, p, bitcast<u32>(pts[hn(h)].w), pts[hn(h)].xyz, pts[hng(h)].xyz, radiosity_key(selection_seed(id_of(i))));
}

// ---- line 8: candidate densities against Y (k = 1) and intensities ----

@compute @workgroup_size(64)
fn candidate_intensity(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * it.row_n;
    if (i >= it.n || i >= atomicLoad(&state[S_M])) { return; }
    let n = atomicLoad(&state[S_OCCUPIED]);
    var p = 1.0;
    if (n > 0u) {
        let a = answers[i];
        var r2 = 3.4e38;
        if (a.w >= 1u) { r2 = bitcast<f32>(a.x); } else { atomicStore(&state[S_CUT], 1u); }
        p = 1.0 / (f32(n) * PI * r2);
    }
    let l = rsum[i].xyz / f32(it.paths);
    f32s[f_cand(i)] = intensity_of(l, p);
}

// ---- lines 9–17: removals and fills, one workgroup ----

// The sort keys: mode 0 the set's intensities ascending (empty slots last);
// mode 1 occupied slots, unverified first, each part by intensity then
// slot (empty slots last); mode 2 candidates by intensity descending, then
// index (none past m).
fn before(mode: u32, a: u32, b: u32) -> bool {
    let m = atomicLoad(&state[S_M]);
    if (mode == 2u) {
        let va = a < m;
        let vb = b < m;
        if (va != vb) { return va; }
        if (!va) { return a < b; }
        let ia = f32s[f_cand(a)];
        let ib = f32s[f_cand(b)];
        if (ia != ib) { return ia > ib; }
        return a < b;
    }
    let oa = a < it.n && occupied(a);
    let ob = b < it.n && occupied(b);
    if (oa != ob) { return oa; }
    if (!oa) { return a < b; }
    if (mode == 1u) {
        let ga = particles[pid(a)].z != 0.0;
        let gb = particles[pid(b)].z != 0.0;
        if (ga != gb) { return !ga; }
    }
    let ia = particles[psel(a)].w;
    let ib = particles[psel(b)].w;
    if (ia != ib) { return ia < ib; }
    return a < b;
}

// Bitonic sort of the indices 0..np2 by `before`, in u32s' sort scratch.
fn sort_indices(mode: u32, li: u32) {
    for (var i = li; i < it.np2; i = i + 256u) { u32s[u_sort(i)] = i; }
    storageBarrier();
    workgroupBarrier();
    for (var size = 2u; size <= it.np2; size = size * 2u) {
        for (var stride = size / 2u; stride > 0u; stride = stride / 2u) {
            for (var t = li; t < it.np2 / 2u; t = t + 256u) {
                let lo = 2u * t - (t & (stride - 1u));
                let hi = lo + stride;
                let up = (lo & size) == 0u;
                let a = u32s[u_sort(lo)];
                let b = u32s[u_sort(hi)];
                // Ascending blocks put b first when it sorts first.
                if (before(mode, b, a) == up) {
                    u32s[u_sort(lo)] = b;
                    u32s[u_sort(hi)] = a;
                }
            }
            storageBarrier();
            workgroupBarrier();
        }
    }
}

@compute @workgroup_size(256)
fn decide(@builtin(local_invocation_index) li: u32) {
    let n_occ = atomicLoad(&state[S_OCCUPIED]);
    let m = atomicLoad(&state[S_M]);
    // Line 9: M_strong, the candidates above the set's strong quantile.
    sort_indices(0u, li);
    var threshold = -1.0;
    var any = false;
    if (n_occ > 0u) {
        let q = clamp(u32(ceil(it.quantile * f32(n_occ))), 1u, n_occ) - 1u;
        threshold = particles[psel(u32s[u_sort(q)])].w;
        any = true;
    }
    var strong = 0u;
    for (var i = li; i < m; i = i + 256u) {
        if (!any || f32s[f_cand(i)] > threshold) { strong = strong + 1u; }
    }
    wg_u[li] = strong;
    workgroupBarrier();
    let m_strong = scan_wg(li);
    let m_min = min(it.m_max, m_strong);
    // Lines 10–13: the unverified, weakest first, then the weakest valid
    // while fewer than M_min; at most M_max.
    let invalid = atomicLoad(&state[S_INVALID]);
    var remove = min(it.m_max, max(invalid, m_min));
    remove = min(remove, n_occ);
    sort_indices(1u, li);
    for (var r = li; r < remove; r = r + 256u) {
        let s = u32s[u_sort(r)];
        var row = particles[pp(s)];
        row.w = 0.0;
        particles[pp(s)] = row;
    }
    storageBarrier();
    workgroupBarrier();
    // Lines 14–17: the strongest candidates fill the empty slots in slot order.
    sort_indices(2u, li);
    if (li == 0u) {
        var next = 0u;
        var added = 0u;
        for (var s = 0u; s < it.n; s = s + 1u) {
            if (occupied(s)) { continue; }
            if (next >= m) { break; }
            let i = u32s[u_sort(next)];
            next = next + 1u;
            let h = u32s[u_cand(i)];
            let o = bitcast<u32>(pts[hng(h)].w);
            let id = id_of(i);
            particles[pp(s)] = vec4<f32>(pts[hp(h)].xyz, 1.0);
            particles[pn(s)] = pts[hn(h)];
            particles[png(s)] = vec4<f32>(pts[hng(h)].xyz, 0.0);
            particles[pl(s)] = vec4<f32>(0.0);
            particles[psel(s)] = vec4<f32>(rsum[i].xyz / f32(it.paths), 0.0);
            particles[pap(s)] = pts[xp(o)];
            particles[pan(s)] = pts[xn(o)];
            particles[pang(s)] = pts[xng(o)];
            particles[pid(s)] = vec4<f32>(bitcast<f32>(id.x), bitcast<f32>(id.y), 1.0, 0.0);
            u32s[u_added(added)] = s;
            added = added + 1u;
        }
        atomicStore(&state[S_STRONG], m_strong);
        atomicStore(&state[S_WEAKEST], select(0u, remove - invalid, remove > invalid));
        atomicStore(&state[S_REMOVED], remove);
        atomicStore(&state[S_ADDED], added);
        // The new VPLs' radiosity runs on them alone (64 invocations a group).
        atomicStore(&state[S_PATHS_GROUPS], (added * it.paths + 63u) / 64u);
        atomicStore(&state[S_PATHS_GROUPS + 1u], 1u);
        atomicStore(&state[S_PATHS_GROUPS + 2u], 1u);
        atomicStore(&state[S_SUM_GROUPS], (added + 63u) / 64u);
        atomicStore(&state[S_SUM_GROUPS + 1u], 1u);
        atomicStore(&state[S_SUM_GROUPS + 2u], 1u);
        atomicStore(&state[S_STORED], n_occ - remove + added);
        let next_id = id_of(m);
        atomicStore(&state[S_ID_LO], next_id.x);
        atomicStore(&state[S_ID_HI], next_id.y);
    }
}

// ---- line 18: radiosities of the set ----

// The rendering radiosity of each VPL that joined Y.
@compute @workgroup_size(64)
fn added_jobs(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * it.row_n;
    if (i >= it.n) { return; }
    if (i >= atomicLoad(&state[S_ADDED])) {
        job(i, vec3<f32>(0.0), 0u, vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 0.0, 1.0), vec2<u32>(0u));
        return;
    }
    let s = u32s[u_added(i)];
    let idv = particles[pid(s)];
    let vid = vec2<u32>(bitcast<u32>(idv.x), bitcast<u32>(idv.y));
    let nrow = particles[pn(s)];
    job(i, particles[pp(s)].xyz, bitcast<u32>(nrow.w), nrow.xyz, particles[png(s)].xyz, radiosity_key(render_seed(vid)));
}

@compute @workgroup_size(64)
fn added_radiance(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * it.row_n;
    if (i >= it.n || i >= atomicLoad(&state[S_ADDED])) { return; }
    let s = u32s[u_added(i)];
    particles[pl(s)] = vec4<f32>(rsum[i].xyz / f32(it.paths), 0.0);
}

// The lights changed: both estimates of every VPL anew, 2s the selection's
// and 2s + 1 the rendering's.
@compute @workgroup_size(64)
fn relit_jobs(@builtin(global_invocation_id) id: vec3<u32>) {
    let s = id.x + id.y * it.row_n;
    if (s >= it.n) { return; }
    let idv = particles[pid(s)];
    let vid = vec2<u32>(bitcast<u32>(idv.x), bitcast<u32>(idv.y));
    let nrow = particles[pn(s)];
    let p = particles[pp(s)].xyz;
    job(2u * s, p, bitcast<u32>(nrow.w), nrow.xyz, particles[png(s)].xyz, radiosity_key(selection_seed(vid)));
    job(2u * s + 1u, p, bitcast<u32>(nrow.w), nrow.xyz, particles[png(s)].xyz, radiosity_key(render_seed(vid)));
}

@compute @workgroup_size(64)
fn relit_radiance(@builtin(global_invocation_id) id: vec3<u32>) {
    let s = id.x + id.y * it.row_n;
    if (s >= it.n || !occupied(s)) { return; }
    particles[psel(s)] = vec4<f32>(rsum[2u * s].xyz / f32(it.paths), particles[psel(s)].w);
    particles[pl(s)] = vec4<f32>(rsum[2u * s + 1u].xyz / f32(it.paths), particles[pl(s)].w);
}

// ---- line 19 and the output: densities (eq. 8), intensities, fluxes ----

@compute @workgroup_size(64)
fn fluxes(@builtin(global_invocation_id) id: vec3<u32>) {
    let s = id.x + id.y * it.row_n;
    if (s >= it.n) { return; }
    let idv = particles[pid(s)];
    if (!occupied(s)) {
        out[3u * s] = vec4<f32>(0.0);
        out[3u * s + 1u] = vec4<f32>(0.0);
        out[3u * s + 2u] = vec4<f32>(0.0);
        return;
    }
    let n = atomicLoad(&state[S_STORED]);
    // set_densities: the area for a lone VPL, k / (n π r_k²) else.
    var p = 1.0 / max(it.area, 1.17549435e-38);
    if (n > 1u) {
        let a = answers[s];
        var r2 = 3.4e38;
        if (a.w >= 1u) { r2 = bitcast<f32>(a.x); }
        if (a.w < min(it.k, n - 1u)) { atomicStore(&state[S_CUT], 1u); }
        p = f32(a.w) / (f32(n) * PI * r2);
    }
    let l = particles[pl(s)].xyz;
    particles[pl(s)] = vec4<f32>(l, p);
    let sel = particles[psel(s)].xyz;
    particles[psel(s)] = vec4<f32>(sel, intensity_of(sel, p));
    // Φ = L / (n p) (eq. 5 in vpl-core's convention), zero where not finite.
    var flux = l / (f32(n) * p);
    if (!finite(flux.x) || !finite(flux.y) || !finite(flux.z)) { flux = vec3<f32>(0.0); }
    out[3u * s] = vec4<f32>(particles[pp(s)].xyz, idv.x);
    out[3u * s + 1u] = vec4<f32>(particles[pn(s)].xyz, idv.y);
    out[3u * s + 2u] = vec4<f32>(flux, 1.0);
}

// The counters, and the intensities' coefficient of variation.
@compute @workgroup_size(256)
fn stats(@builtin(local_invocation_index) li: u32) {
    var sum = 0.0;
    var count = 0u;
    for (var s = li; s < it.n; s = s + 256u) {
        if (occupied(s)) {
            sum = sum + particles[psel(s)].w;
            count = count + 1u;
        }
    }
    wg_f[li] = sum;
    wg_u[li] = count;
    workgroupBarrier();
    for (var off = 128u; off > 0u; off = off / 2u) {
        if (li < off) {
            wg_f[li] = wg_f[li] + wg_f[li + off];
            wg_u[li] = wg_u[li] + wg_u[li + off];
        }
        workgroupBarrier();
    }
    let total = wg_f[0];
    let n = wg_u[0];
    workgroupBarrier();
    let mean = total / f32(max(n, 1u));
    var sq = 0.0;
    for (var s = li; s < it.n; s = s + 256u) {
        if (occupied(s)) {
            let d = particles[psel(s)].w - mean;
            sq = sq + d * d;
        }
    }
    wg_f[li] = sq;
    workgroupBarrier();
    for (var off = 128u; off > 0u; off = off / 2u) {
        if (li < off) { wg_f[li] = wg_f[li] + wg_f[li + off]; }
        workgroupBarrier();
    }
    if (li != 0u) { return; }
    var cv = 0.0;
    if (n >= 2u && mean > 0.0) { cv = sqrt(wg_f[0] / f32(n - 1u)) / mean; }
    let base = 3u * it.n;
    var row: array<u32, 16>;
    for (var k = 0u; k < 14u; k = k + 1u) { row[k] = atomicLoad(&state[k]); }
    row[S_CV] = bitcast<u32>(cv);
    row[S_CUT] = atomicLoad(&state[S_CUT]);
    for (var r = 0u; r < 4u; r = r + 1u) {
        out[base + r] = vec4<f32>(bitcast<f32>(row[4u * r]), bitcast<f32>(row[4u * r + 1u]), bitcast<f32>(row[4u * r + 2u]), bitcast<f32>(row[4u * r + 3u]));
    }
}
