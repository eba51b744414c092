//! [`SelectionOptions`]: how [`Selection::build`](super::Selection::build) merges cameras, finds
//! holes and sizes its grid, checked before the build.

use crate::nearfield::error::{NearfieldError, Result};

/// Options of [`Selection::build`](super::Selection::build).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectionOptions {
    /// Cameras whose directions lie within this angle (rad) of each other are one vertex. Default 10⁻⁶.
    pub merge_tol_rad: f64,
    /// A triangle whose circumradius exceeds this multiple of the median is a hole; Nearest/Idw4 ignore
    /// cameras farther than this multiple of the median circumradius. Default 4.
    pub hole_factor: f64,
    /// Grid cell size (degrees); `None`: half the median edge of the non-hole triangles, within 0.1…5°.
    pub cell_deg: Option<f64>,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        Self {
            merge_tol_rad: 1e-6,
            hole_factor: 4.0,
            cell_deg: None,
        }
    }
}

impl SelectionOptions {
    /// Checks the options; errors name the field.
    pub fn validate(&self) -> Result<()> {
        if !(self.merge_tol_rad.is_finite() && (0.0..=0.1).contains(&self.merge_tol_rad)) {
            return Err(NearfieldError::invalid(
                "merge_tol_rad",
                format!("{} rad is outside 0…0.1 rad", self.merge_tol_rad),
            ));
        }
        if !(self.hole_factor.is_finite() && self.hole_factor >= 1.0) {
            return Err(NearfieldError::invalid(
                "hole_factor",
                format!("{} must be finite and ≥ 1", self.hole_factor),
            ));
        }
        if let Some(c) = self.cell_deg {
            if !(c.is_finite() && c > 0.0 && c <= 90.0) {
                return Err(NearfieldError::invalid(
                    "cell_deg",
                    format!("{c}° must be finite and in (0, 90]"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::nearfield::layout::Layout;
    use crate::nearfield::select::tests::set;
    use crate::nearfield::select::Selection;

    #[test]
    fn options_are_validated_by_name() {
        let s = set(Layout::Fibonacci { count: 50 });
        for (opts, name) in [
            (
                SelectionOptions {
                    merge_tol_rad: f64::NAN,
                    ..Default::default()
                },
                "merge_tol_rad",
            ),
            (
                SelectionOptions {
                    hole_factor: 0.5,
                    ..Default::default()
                },
                "hole_factor",
            ),
            (
                SelectionOptions {
                    cell_deg: Some(0.0),
                    ..Default::default()
                },
                "cell_deg",
            ),
        ] {
            match Selection::build(&s, &opts) {
                Err(NearfieldError::InvalidArgument { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{other:?}"),
            }
        }
    }
}
