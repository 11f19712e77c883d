// The scene in storage buffers (vpl_gpu::GpuScene) and BVH ray casting:
// closest hit and occlusion. Prepended to every kernel that traces rays.
//
// bvh_nodes: two vec4 per node of a binary BVH (obvhs Bvh2, root 0):
//   [min.xyz, first_index], [max.xyz, prim_count]; an inner node has
//   prim_count 0 and children first_index, first_index + 1; a leaf holds
//   BVH primitives first_index .. first_index + prim_count.
// bvh_tris: three vec4 per BVH primitive, its vertices (xyz; w unused), the
//   same coordinates the CPU's BVH tests (vpl_core::bvh::Bvh::vertices).
// bvh_order: scene triangle of each BVH primitive.
// tri_info: four vec4 per scene triangle: [p0, material], [e1, normals],
//   [e2, area], [ng, -] (integers bit-cast; normals = 0xffffffff when flat).
// tri_normals: three vec4 per shading-normal record.
// materials: two vec4 per material: [albedo, -], [emission, -].

const NO_HIT: f32 = 3.0e38;
const NONE: u32 = 0xffffffffu;
const STACK: u32 = 64u;

@group(0) @binding(0) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> bvh_tris: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> bvh_order: array<u32>;
@group(0) @binding(3) var<storage, read> tri_info: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> tri_normals: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> materials: array<vec4<f32>>;

struct Hit {
    t: f32,
    // BVH primitive (not the scene triangle: see bvh_order), NONE for a miss.
    prim: u32,
}

// The ray parameter of the hit with BVH primitive k in [0, t_max], or NO_HIT:
// the watertight test of Woop, Benthin & Wald (2013), as vpl_core::bvh's
// (the ray sheared so that its direction is +z, the edge functions U, V, W
// of the sheared vertices, t = T / det). WGSL has no portable f64, so the
// CPU's double-precision recomputation of edge functions that round to
// exactly zero is left out: the two may decide differently for a ray that
// passes exactly through an edge.
fn tri_test(k: u32, o: vec3<f32>, d: vec3<f32>, t_max: f32) -> f32 {
    let a = bvh_tris[3u * k].xyz - o;
    let b = bvh_tris[3u * k + 1u].xyz - o;
    let c = bvh_tris[3u * k + 2u].xyz - o;
    let ad = abs(d);
    var kz = 2u;
    if (ad.x > ad.y) {
        if (ad.x > ad.z) { kz = 0u; }
    } else if (ad.y > ad.z) {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kz + 2u) % 3u;
    if (d[kz] < 0.0) {
        let swap = kx;
        kx = ky;
        ky = swap;
    }
    let sx = d[kx] / d[kz];
    let sy = d[ky] / d[kz];
    let sz = 1.0 / d[kz];
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) { return NO_HIT; }
    let det = u + v + w;
    if (det == 0.0) { return NO_HIT; }
    let t = u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz]);
    if (det > 0.0) {
        if (t < 0.0 || t > t_max * det) { return NO_HIT; }
    } else {
        if (t > 0.0 || t < t_max * det) { return NO_HIT; }
    }
    let r = t / det;
    if (!(r >= 0.0)) { return NO_HIT; }
    return r;
}

// Entry distance of the ray into node i's box within [0, t_max], or NO_HIT.
fn box_test(i: u32, o: vec3<f32>, inv_d: vec3<f32>, t_max: f32) -> f32 {
    let a = bvh_nodes[2u * i].xyz;
    let b = bvh_nodes[2u * i + 1u].xyz;
    let t0 = (a - o) * inv_d;
    let t1 = (b - o) * inv_d;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let t_near = max(max(lo.x, lo.y), max(lo.z, 0.0));
    let t_far = min(min(hi.x, hi.y), min(hi.z, t_max));
    return select(NO_HIT, t_near, t_near <= t_far);
}

// 1/d with components below 1e-20 in magnitude replaced by +1e-20, so slab
// distances stay finite (and -0.0 needs no special case).
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    return 1.0 / select(d, vec3<f32>(1e-20), abs(d) < vec3<f32>(1e-20));
}

// The closest hit within (0, t_max]; any_hit = true stops at the first one
// (occlusion). Ordered traversal: the nearer child first, the farther on a
// stack with its entry distance, skipped when a closer hit was found since.
fn trace(o: vec3<f32>, d: vec3<f32>, t_max: f32, any_hit: bool) -> Hit {
    var best = Hit(min(t_max, NO_HIT), NONE);
    let inv_d = safe_inverse(d);
    if (box_test(0u, o, inv_d, best.t) == NO_HIT) { return best; }
    var stack_node: array<u32, STACK>;
    var stack_t: array<f32, STACK>;
    var sp = 0u;
    var node = 0u;
    loop {
        let a = bvh_nodes[2u * node];
        let count = bitcast<u32>(bvh_nodes[2u * node + 1u].w);
        let first = bitcast<u32>(a.w);
        var next = NONE;
        if (count > 0u) {
            for (var k = first; k < first + count; k = k + 1u) {
                let t = tri_test(k, o, d, best.t);
                if (t < best.t) {
                    best = Hit(t, k);
                    if (any_hit) { return best; }
                }
            }
        } else {
            let t0 = box_test(first, o, inv_d, best.t);
            let t1 = box_test(first + 1u, o, inv_d, best.t);
            if (t0 != NO_HIT && t1 != NO_HIT) {
                let near_first = t0 <= t1;
                next = select(first + 1u, first, near_first);
                if (sp < STACK) {
                    stack_node[sp] = select(first, first + 1u, near_first);
                    stack_t[sp] = select(t0, t1, near_first);
                    sp = sp + 1u;
                }
            } else if (t0 != NO_HIT) {
                next = first;
            } else if (t1 != NO_HIT) {
                next = first + 1u;
            }
        }
        // Pop until a node that can still hold a closer hit.
        while (next == NONE && sp > 0u) {
            sp = sp - 1u;
            if (stack_t[sp] <= best.t) { next = stack_node[sp]; }
        }
        if (next == NONE) { break; }
        node = next;
    }
    return best;
}

// Barycentrics (b1, b2) of p in triangle (p0, e1, e2), as vpl_core's Scene.
fn barycentrics(p0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, p: vec3<f32>) -> vec2<f32> {
    let v2 = p - p0;
    let d00 = dot(e1, e1);
    let d01 = dot(e1, e2);
    let d11 = dot(e2, e2);
    let d20 = dot(v2, e1);
    let d21 = dot(v2, e2);
    let denom = d00 * d11 - d01 * d01;
    let b1 = clamp((d11 * d20 - d01 * d21) / denom, 0.0, 1.0);
    let b2 = clamp((d00 * d21 - d01 * d20) / denom, 0.0, 1.0 - b1);
    return vec2<f32>(b1, b2);
}

// The surface at point p of the triangle of BVH primitive `prim`, as
// vpl_core's Scene::hit_at: the geometric normal as stored, the shading
// normal interpolated and turned to its side (ng where the triangle is flat
// or the interpolation vanishes).
struct Surface {
    tri: u32,
    material: u32,
    n: vec3<f32>,
    ng: vec3<f32>,
}

fn surface_at(prim: u32, p: vec3<f32>) -> Surface {
    return surface_of(bvh_order[prim], p);
}

// The surface of scene triangle `tri` at `p`, as surface_at.
fn surface_of(tri: u32, p: vec3<f32>) -> Surface {
    let a = tri_info[4u * tri];
    let b = tri_info[4u * tri + 1u];
    let ng = tri_info[4u * tri + 3u].xyz;
    var n = ng;
    let normals = bitcast<u32>(b.w);
    if (normals != NONE) {
        let bc = barycentrics(a.xyz, b.xyz, tri_info[4u * tri + 2u].xyz, p);
        let ns = (tri_normals[3u * normals] * (1.0 - bc.x - bc.y) + tri_normals[3u * normals + 1u] * bc.x + tri_normals[3u * normals + 2u] * bc.y).xyz;
        let len2 = dot(ns, ns);
        if (len2 > 0.0) {
            n = ns * inverseSqrt(len2);
            if (dot(n, ng) < 0.0) { n = -n; }
        }
    }
    return Surface(tri, bitcast<u32>(a.w), n, ng);
}

fn closest_hit(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> Hit {
    return trace(o, d, t_max, false);
}

fn occluded(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> bool {
    return trace(o, d, t_max, true).prim != NONE;
}
