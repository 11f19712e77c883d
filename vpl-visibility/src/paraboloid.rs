//! The hemispherical paraboloid parametrisation (Heidrich & Seidel 1998;
//! Brabec, Annen & Seidel 2002): a unit direction l with l_z ≥ 0 in a frame
//! whose +Z is the VPL normal maps to (u, v) = (l_x, l_y) / (1 + l_z) in the
//! unit disk; the map is the square [−1, 1]² around it.

use vpl_core::glam::{Vec2, Vec3};

/// Paraboloid coordinates of a local unit direction in the upper hemisphere.
#[inline]
pub fn direction_to_paraboloid(l: Vec3) -> Vec2 {
    Vec2::new(l.x, l.y) / (1.0 + l.z)
}

/// The local unit direction at paraboloid coordinates `uv`; points outside
/// the unit disk are pulled onto its rim (the horizon).
#[inline]
pub fn paraboloid_to_direction(uv: Vec2) -> Vec3 {
    let r2 = uv.length_squared();
    let uv = if r2 > 1.0 { uv / r2.sqrt() } else { uv };
    let r2 = r2.min(1.0);
    Vec3::new(2.0 * uv.x, 2.0 * uv.y, 1.0 - r2) / (1.0 + r2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_rim() {
        for l in [Vec3::Z, Vec3::new(0.3, -0.4, 0.866).normalize(), Vec3::new(1.0, 0.0, 1e-4).normalize()] {
            let back = paraboloid_to_direction(direction_to_paraboloid(l));
            assert!((back - l).length() < 1e-4, "{l} -> {back}");
        }
        let rim = paraboloid_to_direction(Vec2::new(1.0, 1.0));
        assert!(rim.z.abs() < 1e-6 && (rim.length() - 1.0).abs() < 1e-6);
    }
}
