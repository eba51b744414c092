//! Where a luminaire hangs in a scene: the issue's `@X,Y,Z[,YAW]` convention as a matrix from the
//! luminaire frame to the scene.
//!
//! Promises:
//! - A scene keeps glTF's coordinates: metres, +Y up. The luminaire frame is the library's
//!   (docs/conventions.md): nadir (γ = 0°) along −Z, C0 along +X, C90 along +Y.
//! - [`placement`]`(x, y, z, yaw)` puts the photometric centre at (x, y, z), the nadir along scene −Y
//!   and C0 along scene +X turned by `yaw` degrees about +Y, positive counter-clockwise seen from
//!   above (right-handed about +Y): at yaw 0 C0 is +X and C90 is −Z; at yaw 90° C0 is −Z. The
//!   matrix is a rotation and a translation (determinant +1), so intensities need no rescaling.
//! - [`Placement::parse`] reads the text `X,Y,Z[,YAW]` (metres, degrees); [`parse_luminaire_arg`]
//!   splits `FILE@X,Y,Z[,YAW]` at its last `@`. Errors name the argument and quote the text.

use std::path::PathBuf;

use glam::{DMat3, DMat4, DVec3};

use super::error::{Result, SceneError};

/// The basis change from the luminaire frame to the scene at yaw 0: X → +X, Y → −Z, Z → +Y.
const SCENE_FROM_LUMINAIRE_AXES: DMat3 = DMat3::from_cols(DVec3::X, DVec3::NEG_Z, DVec3::Y);

/// The matrix from the luminaire frame to the scene of a luminaire whose photometric centre is at
/// (`x_m`, `y_m`, `z_m`) (scene metres), nadir along −Y, C0 along +X turned by `yaw_deg` degrees
/// about +Y (counter-clockwise seen from above).
pub fn placement(x_m: f64, y_m: f64, z_m: f64, yaw_deg: f64) -> DMat4 {
    let turn = DMat3::from_rotation_y(yaw_deg.to_radians());
    let linear = turn * SCENE_FROM_LUMINAIRE_AXES;
    DMat4::from_cols(
        linear.x_axis.extend(0.0),
        linear.y_axis.extend(0.0),
        linear.z_axis.extend(0.0),
        DVec3::new(x_m, y_m, z_m).extend(1.0),
    )
}

/// A luminaire's position and yaw in a scene, as `@X,Y,Z[,YAW]` gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Photometric centre, scene X, metres.
    pub x_m: f64,
    /// Photometric centre, scene Y (up), metres.
    pub y_m: f64,
    /// Photometric centre, scene Z, metres.
    pub z_m: f64,
    /// Turn of C0 about +Y from +X, degrees, counter-clockwise seen from above.
    pub yaw_deg: f64,
}

impl Placement {
    /// Reads `X,Y,Z[,YAW]` (metres, degrees; spaces around the numbers allowed).
    ///
    /// Errors (argument `placement`): not three or four comma-separated numbers, or one that is
    /// not finite; the message quotes the text.
    pub fn parse(text: &str) -> Result<Self> {
        let bad = |why: String| SceneError::invalid("placement", format!("\"{text}\": {why}; expected X,Y,Z[,YAW]"));
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if !(3..=4).contains(&parts.len()) {
            return Err(bad(format!("{} values", parts.len())));
        }
        let mut v = [0.0f64; 4];
        for (k, p) in parts.iter().enumerate() {
            let x: f64 = p.parse().map_err(|_| bad(format!("\"{p}\" is not a number")))?;
            if !x.is_finite() {
                return Err(bad(format!("\"{p}\" is not finite")));
            }
            v[k] = x;
        }
        Ok(Placement {
            x_m: v[0],
            y_m: v[1],
            z_m: v[2],
            yaw_deg: v[3],
        })
    }

    /// The matrix from the luminaire frame to the scene ([`placement`]).
    pub fn matrix(&self) -> DMat4 {
        placement(self.x_m, self.y_m, self.z_m, self.yaw_deg)
    }
}

/// Splits `FILE@X,Y,Z[,YAW]` at its last `@` into the file and its placement.
///
/// Errors (argument `luminaire`): no `@`, an empty file name, and the errors of
/// [`Placement::parse`].
pub fn parse_luminaire_arg(text: &str) -> Result<(PathBuf, Placement)> {
    let Some((file, at)) = text.rsplit_once('@') else {
        return Err(SceneError::invalid(
            "luminaire",
            format!("\"{text}\": no '@'; expected FILE@X,Y,Z[,YAW]"),
        ));
    };
    if file.is_empty() {
        return Err(SceneError::invalid(
            "luminaire",
            format!("\"{text}\": no file before '@'; expected FILE@X,Y,Z[,YAW]"),
        ));
    }
    Ok((PathBuf::from(file), Placement::parse(at)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn nadir_is_down_and_c0_turns_counter_clockwise_about_up() {
        let m = placement(1.0, 2.5, -3.0, 0.0);
        assert!(close(m.transform_vector3(DVec3::NEG_Z), DVec3::NEG_Y), "nadir → −Y");
        assert!(close(m.transform_vector3(DVec3::X), DVec3::X), "C0 → +X at yaw 0");
        assert!(close(m.transform_vector3(DVec3::Y), DVec3::NEG_Z), "C90 → −Z at yaw 0");
        assert!(close(m.transform_point3(DVec3::ZERO), DVec3::new(1.0, 2.5, -3.0)));
        let m90 = placement(0.0, 0.0, 0.0, 90.0);
        assert!(
            close(m90.transform_vector3(DVec3::X), DVec3::NEG_Z),
            "C0 → −Z at yaw 90"
        );
        assert!(
            close(m90.transform_vector3(DVec3::NEG_Z), DVec3::NEG_Y),
            "yaw keeps the nadir"
        );
        // Counter-clockwise seen from above (+Y towards the viewer, looking down): +X turns
        // towards −Z, which is "up the page" when X points right and Z towards the viewer.
        let m30 = placement(0.0, 0.0, 0.0, 30.0);
        let c0 = m30.transform_vector3(DVec3::X);
        let ang = (-c0.z).atan2(c0.x).to_degrees();
        assert!((ang - 30.0).abs() < 1e-9, "{ang}");
        for yaw in [0.0, 17.0, 90.0, -135.0] {
            let d = placement(0.3, 0.2, 0.1, yaw).determinant();
            assert!((d - 1.0).abs() < 1e-12, "det {d} at yaw {yaw}");
        }
    }

    #[test]
    fn parses_positions_with_and_without_yaw() {
        let p = Placement::parse("1.5, 2.95,-0.5").unwrap();
        assert_eq!((p.x_m, p.y_m, p.z_m, p.yaw_deg), (1.5, 2.95, -0.5, 0.0));
        let p = Placement::parse("0,3,0,90").unwrap();
        assert_eq!(p.yaw_deg, 90.0);
        assert!(close(p.matrix().transform_vector3(DVec3::X), DVec3::NEG_Z));
        for bad in ["", "1,2", "1,2,3,4,5", "1,x,3", "1,2,inf", "1,2,NaN"] {
            let e = Placement::parse(bad).unwrap_err().to_string();
            assert!(e.contains("placement") && e.contains(&format!("\"{bad}\"")), "{e}");
        }
        let (f, p) = parse_luminaire_arg("a@b/lum.ies@1,2,3,45").unwrap();
        assert_eq!(f, PathBuf::from("a@b/lum.ies"));
        assert_eq!(p.yaw_deg, 45.0);
        let e = parse_luminaire_arg("lum.ies").unwrap_err().to_string();
        assert!(e.contains("luminaire") && e.contains("no '@'"), "{e}");
        assert!(parse_luminaire_arg("@1,2,3").is_err());
    }
}
