// The visibility of a VPL at a receiver, as the gathers test it: through
// its paraboloid shadow map (vpl_visibility::MapView::visible's test and
// bias) or by a shadow ray (vpl_visibility::RayTraced). A module that
// includes these declares `params` (with res, eps2, texel, eps), `headers`
// and `atlas` as interleaved.wgsl does, and the BVH's `occluded`.

// Whether receiver p (normal n) is visible from the map of `slot`.
fn map_visible(slot: u32, p: vec3<f32>, n: vec3<f32>) -> bool {
    let o = headers[4u * slot];
    let e = p - o.xyz;
    let e2 = dot(e, e);
    if (e2 <= 0.0) { return true; }
    let inv = 1.0 / sqrt(e2);
    let dist = e2 * inv;
    let lz = dot(e, headers[4u * slot + 3u].xyz) * inv;
    if (lz <= 0.0) { return false; }
    let k = inv / (1.0 + lz);
    let half = 0.5 * f32(params.res);
    let top = f32(params.res - 1u);
    let u = clamp((dot(e, headers[4u * slot + 1u].xyz) * k + 1.0) * half, 0.0, top);
    let w = clamp((dot(e, headers[4u * slot + 2u].xyz) * k + 1.0) * half, 0.0, top);
    let depth = atlas[slot * params.res * params.res + u32(w) * params.res + u32(u)];
    let cos_r = abs(-dot(n, e) * inv);
    let tan_r = min(sqrt(max(1.0 - cos_r * cos_r, 0.0)) / max(cos_r, 0.1), 10.0);
    let bias = params.eps2 + params.texel * dist * (1.0 + lz) * (0.5 + tan_r);
    return dist - bias <= depth;
}

// Whether the segment from p (stepped off along n) to the VPL's offset
// origin is unblocked (vpl_core::Scene::visible).
fn ray_visible(y: vec3<f32>, n_y: vec3<f32>, p: vec3<f32>, n: vec3<f32>) -> bool {
    let a = p + n * params.eps;
    let b = y + n_y * params.eps;
    let d = b - a;
    let len = length(d);
    if (len <= 0.0) { return true; }
    return !occluded(a, d / len, len * (1.0 - 1e-4) - params.eps);
}
