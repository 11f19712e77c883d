//! The surface inside a probe's ball: the area A(r) that the hits counted
//! as a probe's neighbours could have landed on, for the probes' area
//! estimate ([`ProbeArea`]).
//!
//! A probe at p stands for b = π r_1² (N − 1) / N ([`crate::AreaProbes`]):
//! with N − 1 other hits drawn from a density that is constant near p,
//! (N − 1) p_h A(r_1) is Exp(1)-distributed, A(r) the area within r of p on
//! which a hit counts as a neighbour. π r² is A(r) where the surface is a
//! plane around p. At a surface's edge A(r) is smaller (half the disk at a
//! straight edge), so π r_1² overstates the area there; in a concave corner
//! the other wall's hits count and A(r) is larger, so π r_1² understates
//! it. [`surface_in_ball`] measures A(r) on the scene's triangles:
//!
//! ```text
//! A(r) = Σ_t |t ∩ B(p, r)|   over the triangles t whose side facing p
//!                            has a normal within 120° of p's (a neighbour
//!                            counts by the same rule) and whose nearest
//!                            point to p is visible from p
//! ```
//!
//! The visibility test keeps the far face of a thin wall out: it lies in
//! the ball, its side facing p is turned toward p, but no ray that hits
//! near p reaches it. It tests one point a triangle: a triangle partly
//! hidden counts whole or not at all.
//!
//! Measured (the `cell_pieces` example of vpl-bench, frame 0, 2048 VPLs,
//! the probes' own radiances with their areas over the path tracer's image
//! mean): `atrium` 0.984, 0.959, 0.994 (seeds 0–2) with the disk, 1.034,
//! 1.006, 1.043 with `surface`, 1.022, 0.997, 1.037 with `smooth`; the
//! Munich blocks 1.057, 1.103, 1.058 with the disk, 1.117, 1.178, 1.160
//! with `surface`, 1.076, 1.207, 1.091 with `smooth`. The exact support
//! moves both scenes up, by 2–10 %, so the disk's error on the Munich
//! blocks is not its edges; the disk stays the default.

use vpl_core::Scene;
use vpl_core::glam::Vec3;
use vpl_core::params::FromParam;

/// The area a probe's ball stands for in the probes' estimate
/// ([`crate::SmcConfig::probe_area`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProbeArea {
    /// π r_1²: the disk, exact where the surface is a plane around the probe.
    #[default]
    Disk,
    /// A(r_1), the scene's surface inside the ball ([`surface_in_ball`]):
    /// exact at edges and in corners too, where the disk is not.
    Surface,
    /// A(r_1) on the probe's own smooth surface: neighbours and the
    /// surface counted within 60° of its normal, so that the hits of
    /// another surface, drawn with another density, do not count.
    Smooth,
}

impl ProbeArea {
    /// Its parameter name.
    pub fn name(self) -> &'static str {
        match self {
            ProbeArea::Disk => "disk",
            ProbeArea::Surface => "surface",
            ProbeArea::Smooth => "smooth",
        }
    }
}

impl FromParam for ProbeArea {
    const EXPECTED: &'static str = "disk, surface or smooth";
    fn from_param(text: &str) -> Option<Self> {
        [ProbeArea::Disk, ProbeArea::Surface, ProbeArea::Smooth].into_iter().find(|a| a.name() == text.trim())
    }
}

impl std::fmt::Display for ProbeArea {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A(r): the area of `scene`'s surface within `r` of `p` on which a hit
/// counts as a neighbour of a hit at `p` with normal `n` (facing the ray
/// that found it): a triangle whose side facing p has a normal whose
/// cosine with `n` is at least `accept` (−0.5 for the side of the surface,
/// 0.5 for the smooth surface). See the module's text for the rule; `out`
/// is scratch.
pub fn surface_in_ball(scene: &Scene, p: Vec3, n: Vec3, r: f32, accept: f32, out: &mut Vec<u32>) -> f32 {
    if !(r.is_finite() && r > 0.0 && p.is_finite() && n.is_finite()) {
        return 0.0;
    }
    let g = &scene.geometry;
    g.bvh.triangles_in_box(p - Vec3::splat(r), p + Vec3::splat(r), out);
    let eps = scene.epsilon();
    let o = p + n * eps;
    let mut area = 0.0f64;
    for &t in out.iter() {
        let Some(tri) = g.triangles.get(t as usize) else { continue };
        if tri.area.is_nan() || tri.area <= 0.0 {
            continue;
        }
        let (a, b, c) = (tri.p0, tri.p0 + tri.e1, tri.p0 + tri.e2);
        // The side of the triangle that faces the probe's open side.
        let m = if (o - a).dot(tri.ng) >= 0.0 { tri.ng } else { -tri.ng };
        if m.dot(n) < accept {
            continue;
        }
        let d = (p - a).dot(m);
        if d.abs() >= r {
            continue;
        }
        let x = closest_on_triangle(p, a, b, c);
        if (x - p).length_squared() >= r * r {
            continue;
        }
        if (x - p).length() > 4.0 * eps && !scene.visible(o, x + m * eps) {
            continue;
        }
        let q = p - m * d;
        area += disk_triangle_area(q, (r * r - d * d).max(0.0).sqrt(), [a, b, c], m);
    }
    area as f32
}

/// The area of the disk of radius `rho` at `q` (in the triangle's plane,
/// normal `m`) inside the triangle `v`: the signed areas of the disk inside
/// the triangles (q, v_i, v_i+1), summed over the edges.
fn disk_triangle_area(q: Vec3, rho: f32, v: [Vec3; 3], m: Vec3) -> f64 {
    if rho <= 0.0 {
        return 0.0;
    }
    // A basis of the plane.
    let u = if m.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let e1 = (u - m * u.dot(m)).normalize();
    let e2 = m.cross(e1);
    let flat = |x: Vec3| {
        let d = x - q;
        (d.dot(e1) as f64, d.dot(e2) as f64)
    };
    let pts = v.map(flat);
    let r = rho as f64;
    let mut sum = 0.0;
    for i in 0..3 {
        sum += disk_wedge(pts[i], pts[(i + 1) % 3], r);
    }
    sum.abs()
}

/// The signed area of the disk of radius `r` at the origin inside the
/// triangle (0, a, b): positive when a → b turns counter-clockwise.
fn disk_wedge(a: (f64, f64), b: (f64, f64), r: f64) -> f64 {
    let cross = |u: (f64, f64), v: (f64, f64)| u.0 * v.1 - u.1 * v.0;
    let dot = |u: (f64, f64), v: (f64, f64)| u.0 * v.0 + u.1 * v.1;
    let sector = |u: (f64, f64), v: (f64, f64)| 0.5 * r * r * cross(u, v).atan2(dot(u, v));
    let r2 = r * r;
    let (la, lb) = (dot(a, a), dot(b, b));
    if la <= r2 && lb <= r2 {
        return 0.5 * cross(a, b);
    }
    let d = (b.0 - a.0, b.1 - a.1);
    let qa = dot(d, d);
    if qa <= 0.0 {
        return 0.0;
    }
    let qb = dot(a, d);
    let disc = qb * qb - qa * (la - r2);
    if disc <= 0.0 {
        return sector(a, b);
    }
    let s = disc.sqrt();
    let (t1, t2) = ((-qb - s) / qa, (-qb + s) / qa);
    if t2 <= 0.0 || t1 >= 1.0 {
        return sector(a, b);
    }
    let at = |t: f64| (a.0 + t * d.0, a.1 + t * d.1);
    let (p1, p2) = (at(t1.max(0.0)), at(t2.min(1.0)));
    let first = if t1 > 0.0 { sector(a, p1) } else { 0.0 };
    let last = if t2 < 1.0 { sector(p2, b) } else { 0.0 };
    first + 0.5 * cross(p1, p2) + last
}

/// The point of the triangle (a, b, c) nearest `p` (Ericson, *Real-Time
/// Collision Detection*, 5.1.5).
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flux::SAME_SIDE_COS;
    use std::f32::consts::PI;
    use vpl_core::Light;
    use vpl_core::material::Material;
    use vpl_core::mesh::Mesh;

    /// The unit floor square (y = 0, x and z in [0, 1]), a wall on its
    /// edge x = 1 when `wall`, and a thin wall's far face 0.01 under the
    /// floor, facing down, when `under`.
    fn scene(wall: bool, under: bool) -> Scene {
        let mut mesh = Mesh::default();
        mesh.push_quad(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0), 0);
        if wall {
            mesh.push_quad(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 0.0), 0);
        }
        if under {
            mesh.push_quad(
                Vec3::new(0.0, -0.01, 0.0),
                Vec3::new(1.0, -0.01, 0.0),
                Vec3::new(1.0, -0.01, 1.0),
                Vec3::new(0.0, -0.01, 1.0),
                0,
            );
        }
        let sun = Light::Directional { direction: Vec3::NEG_Y, irradiance: Vec3::ONE };
        Scene::new("floor", &mesh, vec![Material::diffuse("m", Vec3::splat(0.5))], vec![sun], true).unwrap()
    }

    fn area(s: &Scene, p: Vec3, r: f32) -> f32 {
        surface_in_ball(s, p, Vec3::Y, r, SAME_SIDE_COS, &mut Vec::new())
    }

    /// Inside the floor the ball holds the disk; at its open edge half of
    /// it; at its corner a quarter; against a wall the half disk of the
    /// floor and the half disk of the wall. The thin wall's far face under
    /// the floor is not counted, though it lies in the ball.
    #[test]
    fn the_ball_holds_the_disk_the_half_disk_and_the_corner() {
        let r = 0.1;
        let disk = PI * r * r;
        let close = |got: f32, want: f32, what: &str| assert!((got / want - 1.0).abs() < 1e-4, "{what}: {got} against {want}");
        close(area(&scene(false, true), Vec3::new(0.5, 0.0, 0.5), r), disk, "inside, the far face under it");
        let open = scene(false, false);
        close(area(&open, Vec3::new(0.5, 0.0, 0.5), r), disk, "inside");
        close(area(&open, Vec3::new(0.0, 0.0, 0.5), r), disk / 2.0, "at an edge");
        close(area(&open, Vec3::new(0.0, 0.0, 0.0), r), disk / 4.0, "at a corner");
        // 0.06 from the edge: the disk less the segment beyond it.
        let h = 0.06f32;
        let segment = r * r * (h / r).acos() - h * (r * r - h * h).sqrt();
        close(area(&open, Vec3::new(h, 0.0, 0.5), r), disk - segment, "near an edge");
        let walled = scene(true, false);
        close(area(&walled, Vec3::new(1.0, 0.0, 0.5), r), disk, "against the wall");
        // 0.05 from the wall: the floor's disk and the wall's cap of a ball cut 0.05 from its centre.
        let d = 0.05f32;
        let cap = PI * (r * r - d * d);
        close(
            area(&walled, Vec3::new(1.0 - d, 0.0, 0.5), r),
            disk - (r * r * (d / r).acos() - d * (r * r - d * d).sqrt()) + cap / 2.0,
            "near the wall",
        );
    }

    /// The wedge sums give a polygon's area inside a disk that holds it,
    /// and the disk's area inside a triangle that holds it.
    #[test]
    fn the_disk_inside_a_triangle_and_a_triangle_inside_the_disk() {
        let m = Vec3::Z;
        let big = [Vec3::new(-10.0, -10.0, 0.0), Vec3::new(10.0, -10.0, 0.0), Vec3::new(0.0, 10.0, 0.0)];
        assert!((disk_triangle_area(Vec3::ZERO, 1.0, big, m) - std::f64::consts::PI).abs() < 1e-5);
        let small = [Vec3::new(0.1, 0.1, 0.0), Vec3::new(0.3, 0.1, 0.0), Vec3::new(0.1, 0.4, 0.0)];
        assert!((disk_triangle_area(Vec3::ZERO, 1.0, small, m) - 0.03).abs() < 1e-6);
        let away = [Vec3::new(5.0, 5.0, 0.0), Vec3::new(6.0, 5.0, 0.0), Vec3::new(5.0, 6.0, 0.0)];
        assert!(disk_triangle_area(Vec3::ZERO, 1.0, away, m).abs() < 1e-9);
    }
}
