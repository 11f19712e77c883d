// Radiosity estimates L(y) of surface points by path tracing with next-event
// estimation and MIS, twin of vpl_pathtrace::PathRadiosity (the walk of
// PathTracer::reflected, min_k = 1, max_k = 1 + max_bounces, Russian
// roulette from rr_depth vertices): one invocation a (point, path), the
// same PCG32 streams as the CPU (vpl_core::rng::keyed_state of the point's
// stream key and the path's index, computed here on 32-bit words).
// Entry `sum` then adds each point's paths in path order, as the CPU twin
// adds them, so only one sum a point crosses back to the host.
//
// Entry `track`: tracked pixels' ground truth, twin of
// vpl_pathtrace::track_chunk (PathTracer::li through a pixel): one
// invocation a chunk of a pixel's samples, writing the chunk's sum, sample
// count and sum of squares to out_l. A pixel's chunks are padded to whole
// blocks of `block` (the padding takes no samples); `track_sum` then adds
// each block's chunks in order into out_sum, which is what crosses back.
// jobs holds the camera (five rows, as camera_ray_of reads them, the
// footprint in raster.w: 0 the centre, 1 the box) and then one row a
// pixel (x, y); rng_key the one key of the chunks' streams. Invocation j
// of a dispatch is chunk `first + j` of the padded sequence, `chunks` a
// pixel.
//
// jobs: three vec4 per point: [p, material], [n, two flags], [ng, -].
// rng_key: per point the stream key (lo, hi) of its radiosity streams.
// lights: four vec4 per light: [type (0 area, 1 point, 2 spot, 3 sun,
//   4 environment), triangle, spot cos_total, -], [position or direction,
//   or the sky's zenith, -], [radiance / intensity / irradiance, or the
//   sky's horizon, -], [spot direction, cos_falloff_start, or the sky's nadir].
// light_cdf, light_pmf: the power distribution (vpl_core Distribution1D).
// tri_light: the light of each emissive triangle, NONE elsewhere.

struct Params {
    jobs: u32,
    paths: u32,
    max_k: u32,
    rr_depth: u32,
    lights: u32,
    two_sided: u32,
    eps: f32,
    row: u32,
    // Index of the environment light, NONE without one.
    env: u32,
    // `row` of the `sum` dispatch.
    sum_row: u32,
    // Fewest scattering vertices a counted path has (1 for radiosity).
    min_k: u32,
    // The clamp's G_max of the segment leaving the first vertex, negative
    // for none.
    g_max: f32,
    // `track`: the first chunk of this dispatch, and chunks per pixel.
    first: u32,
    chunks: u32,
    // `track_sum`: chunks a block adds (a power of two, at most 64).
    block: u32,
    pad1: u32,
}

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> jobs: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> rng_key: array<vec2<u32>>;
@group(1) @binding(3) var<storage, read> lights: array<vec4<f32>>;
@group(1) @binding(4) var<storage, read> light_cdf: array<f32>;
@group(1) @binding(5) var<storage, read> light_pmf: array<f32>;
@group(1) @binding(6) var<storage, read> tri_light: array<u32>;
@group(1) @binding(7) var<storage, read_write> out_l: array<vec4<f32>>;
@group(1) @binding(8) var<storage, read_write> out_sum: array<vec4<f32>>;

const FRAC_1_PI: f32 = 0.31830987;
const TWO_PI: f32 = 6.2831855;
// Samples a chunk of `track` (vpl_pathtrace::TRACK_CHUNK).
const CHUNK: u32 = 8u;

fn power_heuristic(pa: f32, pb: f32) -> f32 {
    let a = pa * pa;
    let b = pb * pb;
    if (a + b == 0.0) { return 0.0; }
    return a / (a + b);
}

// ---- lights (vpl_core::Scene::sample_light) ----

struct LightSample {
    ok: bool,
    wi: vec3<f32>,
    dist: f32,
    li: vec3<f32>,
    pdf: f32,
    delta: bool,
    p_sel: f32,
}

fn spot_falloff(cos_theta: f32, start: f32, total: f32) -> f32 {
    if (cos_theta >= start) { return 1.0; }
    if (cos_theta <= total) { return 0.0; }
    let t = clamp((cos_theta - total) / (start - total), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// ---- the environment (vpl_core::environment::Sky) ----

fn mean3(c: vec3<f32>) -> f32 {
    return (c.x + c.y + c.z) * (1.0 / 3.0);
}

// Radiance arriving from direction w: linear in height between zenith,
// horizon and nadir.
fn sky_radiance(i: u32, w: vec3<f32>) -> vec3<f32> {
    let y = clamp(w.y, -1.0, 1.0);
    let hor = lights[4u * i + 2u].xyz;
    if (y >= 0.0) { return hor + (lights[4u * i + 1u].xyz - hor) * y; }
    return hor + (lights[4u * i + 3u].xyz - hor) * (-y);
}

// The integrals of the channel mean over the upper and lower halves of y.
fn sky_halves(i: u32) -> vec2<f32> {
    let h = mean3(lights[4u * i + 2u].xyz);
    return vec2<f32>(0.5 * (h + mean3(lights[4u * i + 1u].xyz)), 0.5 * (h + mean3(lights[4u * i + 3u].xyz)));
}

fn sky_pdf(i: u32, w: vec3<f32>) -> f32 {
    let hv = sky_halves(i);
    let total = TWO_PI * (hv.x + hv.y);
    if (total > 0.0) { return mean3(sky_radiance(i, w)) / total; }
    return 0.0;
}

// t in [0, 1] with density proportional to a + (b - a) t.
fn linear_t(u: f32, a: f32, b: f32) -> f32 {
    let den = a + sqrt(max(a * a + (b * b - a * a) * u, 0.0));
    if (den > 0.0) { return clamp(u * (a + b) / den, 0.0, 1.0); }
    return u;
}

fn sky_sample(i: u32, u0: f32, u1: f32) -> vec3<f32> {
    let hv = sky_halves(i);
    let p_up = hv.x / (hv.x + hv.y);
    let h = mean3(lights[4u * i + 2u].xyz);
    var y: f32;
    if (u0 < p_up) {
        y = linear_t(u0 / p_up, h, mean3(lights[4u * i + 1u].xyz));
    } else {
        y = -linear_t(min((u0 - p_up) / (1.0 - p_up), 1.0), h, mean3(lights[4u * i + 3u].xyz));
    }
    let s = sqrt(max(1.0 - y * y, 0.0));
    let phi = TWO_PI * u1;
    return vec3<f32>(s * cos(phi), y, s * sin(phi));
}

fn sample_light(x: vec3<f32>, u_sel: f32, u0: f32, u1: f32) -> LightSample {
    var ls: LightSample;
    ls.ok = false;
    let n = params.lights;
    if (n == 0u) { return ls; }
    // partition_point(c <= u), then skip zero-probability entries.
    var lo = 0u;
    var hi = n;
    loop {
        if (lo >= hi) { break; }
        let mid = (lo + hi) / 2u;
        if (light_cdf[mid] <= u_sel) { lo = mid + 1u; } else { hi = mid; }
    }
    var i = min(lo, n - 1u);
    loop {
        if (!(light_pmf[i] == 0.0 && i + 1u < n)) { break; }
        i = i + 1u;
    }
    ls.p_sel = light_pmf[i];
    let h = lights[4u * i];
    let kind = bitcast<u32>(h.x);
    if (kind == 0u) {
        // Area: a uniform point on the emissive triangle.
        let tri = bitcast<u32>(h.y);
        let p0 = tri_info[4u * tri].xyz;
        let e1 = tri_info[4u * tri + 1u].xyz;
        let e2 = tri_info[4u * tri + 2u];
        let ng = tri_info[4u * tri + 3u].xyz;
        let su = sqrt(u0);
        let b1 = 1.0 - su;
        let b2 = u1 * su;
        let y = p0 + e1 * b1 + e2.xyz * b2;
        let d = y - x;
        let dist2 = dot(d, d);
        if (dist2 <= 0.0) { return ls; }
        let dist = sqrt(dist2);
        let wi = d / dist;
        let cos_l = -dot(wi, ng);
        if (cos_l <= 0.0) { return ls; }
        ls.ok = true;
        ls.wi = wi;
        ls.dist = dist;
        ls.li = lights[4u * i + 2u].xyz;
        ls.pdf = dist2 / (cos_l * e2.w);
        ls.delta = false;
        return ls;
    }
    if (kind == 4u) {
        let hv = sky_halves(i);
        if (!(hv.x + hv.y > 0.0)) { return ls; }
        let w = sky_sample(i, u0, u1);
        let pdf = sky_pdf(i, w);
        if (!(pdf > 0.0)) { return ls; }
        ls.ok = true;
        ls.wi = w;
        ls.dist = NO_HIT;
        ls.li = sky_radiance(i, w);
        ls.pdf = pdf;
        ls.delta = false;
        return ls;
    }
    if (kind == 3u) {
        // Directional (sun).
        ls.ok = true;
        ls.wi = -lights[4u * i + 1u].xyz;
        ls.dist = NO_HIT;
        ls.li = lights[4u * i + 2u].xyz;
        ls.pdf = 1.0;
        ls.delta = true;
        return ls;
    }
    // Point (1) and spot (2).
    let d = lights[4u * i + 1u].xyz - x;
    let dist2 = dot(d, d);
    if (dist2 <= 0.0) { return ls; }
    let dist = sqrt(dist2);
    let wi = d / dist;
    var f = 1.0;
    if (kind == 2u) {
        let sp = lights[4u * i + 3u];
        f = spot_falloff(-dot(wi, sp.xyz), sp.w, h.z);
        if (f <= 0.0) { return ls; }
    }
    ls.ok = true;
    ls.wi = wi;
    ls.dist = dist;
    ls.li = lights[4u * i + 2u].xyz * (f / dist2);
    ls.pdf = 1.0;
    ls.delta = true;
    return ls;
}

// Scene::light_unoccluded: from x stepped off along ng toward the sample.
fn light_unoccluded(x: vec3<f32>, ng: vec3<f32>, ls: LightSample) -> bool {
    let o = x + ng * params.eps;
    if (ls.dist < NO_HIT) {
        let b = x + ls.wi * ls.dist;
        let d = b - o;
        let len = length(d);
        if (len <= 0.0) { return true; }
        return !occluded(o, d / len, len * (1.0 - 1e-4) - params.eps);
    }
    return !occluded(o, ls.wi, NO_HIT);
}

// Scene::light_pdf of point y on triangle tri seen from x.
fn light_pdf(x: vec3<f32>, y: vec3<f32>, tri: u32) -> f32 {
    let li = tri_light[tri];
    if (li == NONE) { return 0.0; }
    let ng = tri_info[4u * tri + 3u].xyz;
    let d = y - x;
    let dist2 = dot(d, d);
    let cos_l = -dot(d / sqrt(dist2), ng);
    if (cos_l <= 0.0) { return 0.0; }
    return light_pmf[li] * dist2 / (cos_l * tri_info[4u * tri + 2u].w);
}

// PathTracer::walk on diffuse materials: the radiance a path brings that
// has reached surface point p (shading normal n, geometric ng, `material`)
// from direction wo (pointing away from p) after k scattering vertices,
// counting paths whose number of vertices lies in min_k..=max_k.
fn walk(p0: vec3<f32>, n0: vec3<f32>, ng0: vec3<f32>, material0: u32, wo0: vec3<f32>, k0: u32) -> vec3<f32> {
    var p = p0;
    var n = n0;
    var ng = ng0;
    var material = material0;
    var wo = wo0;
    var k = k0;
    var l = vec3<f32>(0.0);
    var beta = vec3<f32>(1.0);
    loop {
        if (k + 1u > params.max_k) { break; }
        if (dot(wo, ng) <= 0.0) {
            if (params.two_sided == 0u) { break; }
            ng = -ng;
            n = -n;
        }
        let albedo = materials[2u * material].xyz;
        if (max(max(albedo.x, albedo.y), albedo.z) <= 0.0) { break; }
        let f = albedo * FRAC_1_PI;
        let u_sel = next_f32();
        let u_l0 = next_f32();
        let u_l1 = next_f32();
        let u_b0 = next_f32();
        let u_b1 = next_f32();
        let last = k + 1u == params.max_k;
        // Next-event estimation: a path with k + 1 scattering vertices.
        if (k + 1u >= params.min_k) {
            let ls = sample_light(p, u_sel, u_l0, u_l1);
            if (ls.ok) {
                let cos_i = dot(n, ls.wi);
                if (cos_i > 0.0 && dot(ls.wi, ng) > 0.0 && light_unoccluded(p, ng, ls)) {
                    if (ls.delta) {
                        l = l + beta * f * ls.li * (cos_i / ls.p_sel);
                    } else {
                        let pdf_light = ls.p_sel * ls.pdf;
                        var w = 1.0;
                        if (!last) { w = power_heuristic(pdf_light, cos_i * FRAC_1_PI); }
                        l = l + beta * f * ls.li * (cos_i * w / pdf_light);
                    }
                }
            }
        }
        if (last) { break; }
        let local = cosine_hemisphere(u_b0, u_b1);
        let wi = to_world(n, local);
        if (dot(wi, ng) <= 0.0) { break; }
        let pdf_bsdf = local.z * FRAC_1_PI;
        beta = beta * albedo;
        let origin = p + ng * params.eps;
        let h = closest_hit(origin, wi, NO_HIT);
        if (h.prim == NONE) {
            // Leaving the scene: the environment ends a path with k + 1
            // vertices, weighted against NEE.
            if (params.env != NONE && k + 1u >= params.min_k) {
                let le = sky_radiance(params.env, wi);
                if (max(max(le.x, le.y), le.z) > 0.0) {
                    l = l + beta * le * power_heuristic(pdf_bsdf, light_pmf[params.env] * sky_pdf(params.env, wi));
                }
            }
            break;
        }
        k = k + 1u;
        // The next vertex, as Scene::hit_at.
        let q = origin + wi * h.t;
        let sf = surface_at(h.prim, q);
        let tri = sf.tri;
        let tng = sf.ng;
        let qn = sf.n;
        let q_material = sf.material;
        // Emission at the next vertex: a path with k vertices, weighted against NEE.
        if (k >= params.min_k && dot(-wi, tng) > 0.0) {
            let le = materials[2u * q_material + 1u].xyz;
            if (max(max(le.x, le.y), le.z) > 0.0) {
                let w = power_heuristic(pdf_bsdf, light_pdf(p, q, tri));
                l = l + beta * le * w;
            }
        }
        // The clamp of the segment that leaves the first vertex, min(G,
        // G_max) / G with G = cos·cos / t² (vpl_core::clamp::geometry_term).
        if (k == 1u && params.g_max >= 0.0) {
            let g = max(local.z, 0.0) * max(abs(dot(qn, -wi)), 0.0) / (h.t * h.t);
            if (g > params.g_max) { beta = beta * (params.g_max / g); }
        }
        if (k >= params.rr_depth) {
            let qq = min(max(max(beta.x, beta.y), beta.z), 0.95);
            if (next_f32() >= qq) { break; }
            beta = beta / qq;
        }
        p = q;
        n = qn;
        ng = tng;
        material = q_material;
        wo = -wi;
    }
    return l;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let k_job = id.x + id.y * params.row;
    if (k_job >= params.jobs * params.paths) { return; }
    let job = k_job / params.paths;
    seed_stream(k_job - job * params.paths, rng_key[job]);
    let a = jobs[3u * job];
    let n = jobs[3u * job + 1u].xyz;
    out_l[k_job] = vec4<f32>(walk(a.xyz, n, jobs[3u * job + 2u].xyz, bitcast<u32>(a.w), n, 0u), 0.0);
}

// PathTracer::li of the camera ray through raster (px, py) with lens
// sample (lu, lv).
fn li(px: f32, py: f32, lu: f32, lv: f32) -> vec3<f32> {
    let ray = camera_ray_at(jobs[0], jobs[1], jobs[2], jobs[3], jobs[4], px, py, lu, lv);
    let h = closest_hit(ray.o, ray.d, NO_HIT);
    if (h.prim == NONE) {
        // The environment seen directly: a path without scattering vertices.
        if (params.min_k == 0u && params.env != NONE) { return sky_radiance(params.env, ray.d); }
        return vec3<f32>(0.0);
    }
    let q = ray.o + ray.d * h.t;
    let sf = surface_at(h.prim, q);
    var l = vec3<f32>(0.0);
    if (params.min_k == 0u && dot(-ray.d, sf.ng) > 0.0) {
        l = materials[2u * sf.material + 1u].xyz;
    }
    return l + walk(q, sf.n, sf.ng, sf.material, -ray.d, 0u);
}

// One chunk of a tracked pixel's samples (vpl_pathtrace::track_chunk):
// its sum and sum of squares.
@compute @workgroup_size(64)
fn track(@builtin(global_invocation_id) id: vec3<u32>) {
    let j = id.x + id.y * params.row;
    if (j >= params.jobs) { return; }
    let g = params.first + j;
    let pixel = g / params.chunks;
    let chunk = g - pixel * params.chunks;
    let n = min(params.paths - min(chunk * CHUNK, params.paths), CHUNK);
    seed_stream64(vec2<u32>(chunk, pixel), rng_key[0]);
    let xy = jobs[5u + pixel].xy;
    let boxed = jobs[4].w > 0.5;
    var sum = vec3<f32>(0.0);
    var sum_sq = vec3<f32>(0.0);
    // Samples taken: fewer than n where a device cuts loops short.
    var done = 0u;
    for (var i = 0u; i < n; i = i + 1u) {
        var u = 0.5;
        var v = 0.5;
        if (boxed) {
            u = next_f32();
            v = next_f32();
        }
        let lu = next_f32();
        let lv = next_f32();
        let l = li(xy.x + u, xy.y + v, lu, lv);
        sum = sum + l;
        sum_sq = sum_sq + l * l;
        done = done + 1u;
    }
    out_l[2u * j] = vec4<f32>(sum, f32(done));
    out_l[2u * j + 1u] = vec4<f32>(sum_sq, 0.0);
}

// Block b of a `track` dispatch: its `block` chunks' sums, counts and sums
// of squares added in chunk order.
@compute @workgroup_size(64)
fn track_sum(@builtin(global_invocation_id) id: vec3<u32>) {
    let b = id.x + id.y * params.sum_row;
    let m = params.block;
    if (b * m >= params.jobs) { return; }
    var s = vec4<f32>(0.0);
    var s2 = vec4<f32>(0.0);
    for (var i = 0u; i < m; i = i + 1u) {
        s = s + out_l[2u * (b * m + i)];
        s2 = s2 + out_l[2u * (b * m + i) + 1u];
    }
    out_sum[2u * b] = s;
    out_sum[2u * b + 1u] = s2;
}

// The sum of each point's paths, added in path order.
@compute @workgroup_size(64)
fn sum(@builtin(global_invocation_id) id: vec3<u32>) {
    let job = id.x + id.y * params.sum_row;
    if (job >= params.jobs) { return; }
    var l = vec3<f32>(0.0);
    for (var i = 0u; i < params.paths; i = i + 1u) {
        l = l + out_l[job * params.paths + i].xyz;
    }
    out_sum[job] = vec4<f32>(l, 0.0);
}
