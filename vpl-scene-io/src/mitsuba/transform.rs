//! `<transform>` steps: `translate`, `scale`, `rotate`, `matrix` and
//! `lookat`, each applied after the ones before it (the matrix of a
//! transform is its last step's times … times its first's).

use super::xml::{parse_f32, parse_list, vec3_attr};
use glam::{Mat4, Vec3, Vec4};
use std::collections::HashMap;

/// The matrix of one step `<tag …attrs>`.
pub(crate) fn op(tag: &str, attrs: &HashMap<String, String>) -> Result<Mat4, String> {
    let a = |k: &str| attrs.get(k).cloned();
    let known = |names: &[&str]| -> Result<(), String> {
        match attrs.keys().find(|k| !names.contains(&k.as_str())) {
            Some(k) => Err(format!("unknown attribute {k}")),
            None => Ok(()),
        }
    };
    Ok(match tag {
        "translate" => {
            known(&["x", "y", "z", "value"])?;
            Mat4::from_translation(vec3_attr(&a("value"), &a("x"), &a("y"), &a("z"), 0.0)?)
        }
        "scale" => {
            known(&["x", "y", "z", "value"])?;
            let s = vec3_attr(&a("value"), &a("x"), &a("y"), &a("z"), 1.0)?;
            Mat4::from_scale(s)
        }
        "rotate" => {
            known(&["x", "y", "z", "value", "angle"])?;
            let axis = vec3_attr(&a("value"), &a("x"), &a("y"), &a("z"), 0.0)?;
            let angle = parse_f32(&a("angle").ok_or("needs an angle (degrees)")?)?;
            let axis = axis.try_normalize().ok_or("needs a nonzero axis")?;
            Mat4::from_axis_angle(axis, angle.to_radians())
        }
        "matrix" => {
            known(&["value"])?;
            let v = a("value").ok_or("needs a value (16 or 9 numbers, row by row)")?;
            let xs = parse_list(&v)?;
            match xs.len() {
                16 => Mat4::from_cols_array(&xs.try_into().map_err(|_| "16 numbers")?).transpose(),
                9 => Mat4::from_cols(
                    Vec4::new(xs[0], xs[3], xs[6], 0.0),
                    Vec4::new(xs[1], xs[4], xs[7], 0.0),
                    Vec4::new(xs[2], xs[5], xs[8], 0.0),
                    Vec4::W,
                ),
                n => return Err(format!("has {n} numbers, not 16 or 9")),
            }
        }
        "lookat" => {
            known(&["origin", "target", "up"])?;
            let p = |k: &str| -> Result<Vec3, String> {
                let v = a(k).ok_or_else(|| format!("needs {k}"))?;
                match parse_list(&v)?.as_slice() {
                    [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                    _ => Err(format!("{k}='{v}' is not three numbers")),
                }
            };
            let origin = p("origin")?;
            let target = p("target")?;
            let up = if attrs.contains_key("up") { p("up")? } else { Vec3::Y };
            look_at(origin, target, up).ok_or("origin and target coincide, or up is parallel to the view")?
        }
        t => return Err(format!("<{t}> is not a transform step (translate, scale, rotate, matrix, lookat)")),
    })
}

/// Mitsuba's look-at frame: local +Z looks at `target`, +Y is up and +X
/// is left (`up × dir`), placed at `origin`.
pub(crate) fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - origin).try_normalize()?;
    let left = up.cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    Some(Mat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attrs(kv: &[(&str, &str)]) -> HashMap<String, String> {
        kv.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    #[test]
    fn matrix_is_row_major() {
        let m = op("matrix", &attrs(&[("value", "1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1")])).unwrap();
        assert_eq!(m.transform_point3(Vec3::ZERO), Vec3::new(5.0, 6.0, 7.0));
    }

    #[test]
    fn rotate_is_counter_clockwise_about_its_axis() {
        let m = op("rotate", &attrs(&[("y", "1"), ("angle", "90")])).unwrap();
        assert!((m.transform_vector3(Vec3::Z) - Vec3::X).length() < 1e-6);
        assert!(op("rotate", &attrs(&[("angle", "90")])).is_err());
    }

    #[test]
    fn lookat_frame_has_left_handed_x() {
        let m = look_at(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO, Vec3::Y).unwrap();
        assert!((m.transform_vector3(Vec3::Z) - Vec3::Z).length() < 1e-6);
        // Looking along +Z with +Y up, local +X (left) is world +X.
        assert!((m.transform_vector3(Vec3::X) - Vec3::X).length() < 1e-6);
        assert!(m.determinant() > 0.0);
        assert!(look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y).is_none());
    }

    #[test]
    fn unknown_step_and_attribute_are_errors() {
        assert!(op("shear", &attrs(&[])).unwrap_err().contains("not a transform step"));
        assert!(op("translate", &attrs(&[("w", "1")])).unwrap_err().contains("unknown attribute w"));
    }
}
