//! Luminous openings: the emitting surface a photometric file declares, in metres in the
//! luminaire frame (extents along X = C0–C180, Y = C90–C270 and Z), its projected area
//! A_proj(C, γ) seen from a direction, and the luminance L = I / A_proj. The formula for every
//! shape is written out in docs/photometry.md.
//!
//! The opening is stored by axis, never by a format's own words: which of a file's "length" and
//! "width" lies along X is the format's rule (docs/adr/0002-luminous-dimensions-per-format.md).
//! IES LM-63 measures its length along the 0–180° plane (X) and its width along the 90–270° plane
//! (Y); EULUMDAT, as Relux reads it, runs the length along C90–C270 (Y), and its C0 side height
//! is the face seen from C0 (normal +X), which spans that length.

use std::f64::consts::PI;

use super::web::direction;

/// The shape of a luminous opening.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum OpeningShape {
    /// No extent (IES 0, 0, 0): luminance is undefined.
    Point,
    /// Flat horizontal rectangle, X × Y.
    Rectangle,
    /// Rectangle with luminous sides of one height (IES w, l, h > 0): a box.
    Box,
    /// Flat horizontal ellipse (a disc when length = width).
    Ellipse,
    /// Vertical cylinder with elliptic (or circular) cross-section X × Y, height h.
    VerticalCylinder,
    /// Ellipsoid with axes X, Y, height (a sphere when all are equal).
    Ellipsoid,
    /// Horizontal cylinder along X (IES: along the length); cross-section Y × height.
    HorizontalCylinderAlongLength,
    /// Horizontal cylinder along Y (IES: along the width); cross-section X × height.
    HorizontalCylinderAlongWidth,
    /// Flat vertical ellipse facing C0 (normal ±X), Y × height.
    VerticalEllipseFacingC0,
    /// Flat vertical ellipse facing C90 (normal ±Y), X × height.
    VerticalEllipseFacingC90,
    /// EULUMDAT luminous area: a rectangle (X × Y) with its own side heights on the faces seen
    /// from C0, C90, C180 and C270.
    RectangleWithSides,
    /// EULUMDAT luminous area: a disc (diameter = X = Y) with side heights on the quarters seen
    /// from C0, C90, C180, C270.
    DiscWithSides,
}

/// A luminous opening in metres.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LuminousOpening {
    /// Its shape.
    pub shape: OpeningShape,
    /// Extent along X (the C0–C180 axis), m. Diameter for discs. IES: the length; EULUMDAT: the
    /// width (docs/adr/0002-luminous-dimensions-per-format.md).
    pub size_x_m: f64,
    /// Extent along Y (the C90–C270 axis), m. IES: the width; EULUMDAT: the length.
    pub size_y_m: f64,
    /// Extent along Z, m.
    pub height_m: f64,
    /// Heights in m of the side faces seen from C0, C90, C180 and C270, i.e. of the faces whose
    /// outward normals are +X, +Y, −X and −Y (EULUMDAT shapes only; zero otherwise). The C0 face
    /// spans the Y extent, the C90 face the X extent.
    pub side_heights_m: [f64; 4],
}

impl LuminousOpening {
    /// A point opening.
    pub fn point() -> Self {
        LuminousOpening {
            shape: OpeningShape::Point,
            size_x_m: 0.0,
            size_y_m: 0.0,
            height_m: 0.0,
            side_heights_m: [0.0; 4],
        }
    }

    /// An opening of `shape` with its extents along X, Y and Z in metres.
    pub fn new(shape: OpeningShape, size_x_m: f64, size_y_m: f64, height_m: f64) -> Self {
        LuminousOpening {
            shape,
            size_x_m,
            size_y_m,
            height_m,
            side_heights_m: [0.0; 4],
        }
    }

    /// Projected area in m² of the opening seen from the unit direction `d` (luminaire frame,
    /// pointing from the luminaire towards the observer). Flat surfaces count from both sides.
    pub fn projected_area_dir(&self, d: [f64; 3]) -> f64 {
        let (l, w, h) = (self.size_x_m, self.size_y_m, self.height_m);
        let (dx, dy, dz) = (d[0].abs(), d[1].abs(), d[2].abs());
        let q = PI / 4.0;
        match self.shape {
            OpeningShape::Point => 0.0,
            OpeningShape::Rectangle => l * w * dz,
            OpeningShape::Box => l * w * dz + w * h * dx + l * h * dy,
            OpeningShape::Ellipse => q * l * w * dz,
            OpeningShape::VerticalCylinder => q * l * w * dz + h * (l * l * dy * dy + w * w * dx * dx).sqrt(),
            OpeningShape::Ellipsoid => {
                let (a, b, c) = (l / 2.0, w / 2.0, h / 2.0);
                PI * ((b * c * dx).powi(2) + (a * c * dy).powi(2) + (a * b * dz).powi(2)).sqrt()
            }
            OpeningShape::HorizontalCylinderAlongLength => {
                q * w * h * dx + l * (w * w * dz * dz + h * h * dy * dy).sqrt()
            }
            OpeningShape::HorizontalCylinderAlongWidth => {
                q * l * h * dy + w * (l * l * dz * dz + h * h * dx * dx).sqrt()
            }
            OpeningShape::VerticalEllipseFacingC0 => q * w * h * dx,
            OpeningShape::VerticalEllipseFacingC90 => q * l * h * dy,
            OpeningShape::RectangleWithSides => {
                let [h0, h90, h180, h270] = self.side_heights_m;
                l * w * dz
                    + w * (h0 * d[0].max(0.0) + h180 * (-d[0]).max(0.0))
                    + l * (h90 * d[1].max(0.0) + h270 * (-d[1]).max(0.0))
            }
            OpeningShape::DiscWithSides => {
                let [h0, h90, h180, h270] = self.side_heights_m;
                let s = (d[0] * d[0] + d[1] * d[1]).sqrt(); // sin γ
                let side = if s > 0.0 {
                    // Height seen from this azimuth: the side heights weighted by how squarely
                    // each quarter faces the direction (equal heights give exactly h).
                    let (cx, cy) = (d[0] / s, d[1] / s);
                    let wts = [cx.max(0.0), cy.max(0.0), (-cx).max(0.0), (-cy).max(0.0)];
                    let hs = [h0, h90, h180, h270];
                    let sum: f64 = wts.iter().sum();
                    let h_eff: f64 = wts.iter().zip(hs).map(|(a, b)| a * b).sum::<f64>() / sum;
                    l * h_eff * s
                } else {
                    0.0
                };
                q * l * l * dz + side
            }
        }
    }

    /// Projected area in m² seen from Type C angles (degrees).
    pub fn projected_area(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        self.projected_area_dir(direction(c_deg, gamma_deg))
    }

    /// True when the opening has no area from any direction (a point or degenerate size).
    pub fn is_point(&self) -> bool {
        self.shape == OpeningShape::Point
            || (0..=8).all(|i| {
                let g = i as f64 * 22.5;
                (0..8).all(|j| self.projected_area(j as f64 * 45.0, g) <= 0.0)
            })
    }
}

/// Smallest projected area (m²) treated as non-zero when dividing intensity by it.
pub const MIN_AREA_M2: f64 = 1e-12;

/// Luminance in cd/m² for an intensity `cd` seen across `area_m2`; `None` where the area is zero
/// (a point opening, or a flat opening seen edge-on).
pub fn luminance(cd: f64, area_m2: f64) -> Option<f64> {
    (area_m2 > MIN_AREA_M2).then(|| cd / area_m2)
}

/// Classifies IES luminous dimensions (width, length, height, already in metres) into a shape,
/// following the LM-63-2019 Table 1 sign conventions. The length lies along X (the 0–180° plane),
/// the width along Y (the 90–270° plane). `legacy` selects the pre-2002 reading: one
/// negative horizontal dimension with the other positive is an ellipse (flat, or with luminous
/// sides when the height is positive) or, with a negative height, an ellipsoid; and a zero length
/// or width takes the value of the negative (round) dimension next to it. Returns the opening and
/// a warning for sign patterns outside the table.
pub fn classify_ies(w: f64, l: f64, h: f64, legacy: bool) -> (LuminousOpening, Option<String>) {
    let (mut w, mut l, h) = (w, l, h);
    if legacy && ((w < 0.0 && l > 0.0) || (w > 0.0 && l < 0.0)) {
        let shape = if h < 0.0 {
            OpeningShape::Ellipsoid
        } else if h > 0.0 {
            OpeningShape::VerticalCylinder
        } else {
            OpeningShape::Ellipse
        };
        return (LuminousOpening::new(shape, l.abs(), w.abs(), h.abs()), None);
    }
    if legacy {
        if l == 0.0 && w < 0.0 {
            l = w;
        } else if w == 0.0 && l < 0.0 {
            w = l;
        } else if w == 0.0 && l > 0.0 && h < 0.0 {
            w = h;
        } else if l == 0.0 && w > 0.0 && h < 0.0 {
            l = h;
        }
    }
    let sgn = |x: f64| {
        if x > 0.0 {
            1
        } else if x < 0.0 {
            -1
        } else {
            0
        }
    };
    let (al, aw, ah) = (l.abs(), w.abs(), h.abs());
    let make = |s| LuminousOpening::new(s, al, aw, ah);
    use OpeningShape as S;
    let table = match (sgn(w), sgn(l), sgn(h)) {
        (0, 0, 0) => Some(LuminousOpening::point()),
        (1, 1, 0) => Some(make(S::Rectangle)),
        (1, 1, 1) => Some(make(S::Box)),
        (-1, -1, 0) => Some(make(S::Ellipse)),
        (-1, -1, 1) => Some(make(S::VerticalCylinder)),
        (-1, -1, -1) => Some(make(S::Ellipsoid)),
        (-1, 1, -1) => Some(make(S::HorizontalCylinderAlongLength)),
        (1, -1, -1) => Some(make(S::HorizontalCylinderAlongWidth)),
        (-1, 0, -1) => Some(make(S::VerticalEllipseFacingC0)),
        (0, -1, -1) => Some(make(S::VerticalEllipseFacingC90)),
        _ => None,
    };
    if let Some(o) = table {
        return (o, None);
    }
    // Outside the table: a negative horizontal dimension means a round outline, otherwise
    // rectangular; the height's sign picks flat, vertical sides, or a solid.
    let round = w < 0.0 || l < 0.0;
    let shape = match (round, sgn(h)) {
        (true, 0) => S::Ellipse,
        (true, 1) => S::VerticalCylinder,
        (true, _) => S::Ellipsoid,
        (false, 0) => S::Rectangle,
        (false, _) => S::Box,
    };
    let o = make(shape);
    let warning = format!(
        "luminous dimensions (width {w}, length {l}, height {h}) match no LM-63-2019 shape; read as {shape:?} \
         {al} × {aw} × {ah} m"
    );
    (o, Some(warning))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 + 1e-9 * b.abs()
    }

    #[test]
    fn rectangle_area_follows_cos_gamma() {
        let o = LuminousOpening::new(OpeningShape::Rectangle, 0.6, 0.3, 0.0);
        assert!(close(o.projected_area(0.0, 0.0), 0.18));
        assert!(close(o.projected_area(37.0, 60.0), 0.09));
        assert!(o.projected_area(0.0, 90.0) < 1e-15);
    }

    #[test]
    fn sphere_is_the_same_from_everywhere() {
        let o = LuminousOpening::new(OpeningShape::Ellipsoid, 0.2, 0.2, 0.2);
        for (c, g) in [(0.0, 0.0), (33.0, 71.0), (200.0, 150.0)] {
            assert!(close(o.projected_area(c, g), PI * 0.01));
        }
    }

    #[test]
    fn cylinders_from_the_side_and_the_axis() {
        let v = LuminousOpening::new(OpeningShape::VerticalCylinder, 0.2, 0.2, 0.5);
        assert!(close(v.projected_area(0.0, 0.0), PI * 0.01));
        assert!(close(v.projected_area(123.0, 90.0), 0.1));
        let hl = LuminousOpening::new(OpeningShape::HorizontalCylinderAlongLength, 1.0, 0.1, 0.1);
        assert!(close(hl.projected_area(0.0, 90.0), PI * 0.0025)); // end-on
        assert!(close(hl.projected_area(90.0, 90.0), 0.1)); // side
        assert!(close(hl.projected_area(0.0, 0.0), 0.1)); // from below
    }

    #[test]
    fn ies_shape_table() {
        let s = |w, l, h, legacy| classify_ies(w, l, h, legacy).0.shape;
        assert_eq!(s(0.0, 0.0, 0.0, false), OpeningShape::Point);
        assert_eq!(s(0.1, 0.2, 0.0, false), OpeningShape::Rectangle);
        assert_eq!(s(-0.1, -0.1, 0.0, false), OpeningShape::Ellipse);
        assert_eq!(s(-0.1, -0.1, -0.1, false), OpeningShape::Ellipsoid);
        assert_eq!(s(-0.1, 0.0, -0.1, false), OpeningShape::VerticalEllipseFacingC0);
        // Pre-2002 files: a zero length copies the round width.
        assert_eq!(s(-0.1, 0.0, -0.1, true), OpeningShape::Ellipsoid);
        assert_eq!(s(-0.1, 0.0, 0.0, true), OpeningShape::Ellipse);
        assert_eq!(s(0.0, 0.12, -0.34, true), OpeningShape::HorizontalCylinderAlongLength);
        let (o, warn) = classify_ies(-0.12, 0.34, 0.56, true);
        assert_eq!(o.shape, OpeningShape::VerticalCylinder);
        assert!(warn.is_none());
        assert_eq!(s(-0.12, 0.34, -0.56, true), OpeningShape::Ellipsoid);
        assert_eq!(
            s(-0.12, 0.34, -0.56, false),
            OpeningShape::HorizontalCylinderAlongLength
        );
        let (o, warn) = classify_ies(-0.12, 0.34, 0.56, false);
        assert_eq!(o.shape, OpeningShape::VerticalCylinder);
        assert!(warn.is_some());
    }

    #[test]
    fn disc_with_equal_sides_is_a_cylinder() {
        let mut o = LuminousOpening::new(OpeningShape::DiscWithSides, 0.3, 0.3, 0.0);
        o.side_heights_m = [0.05; 4];
        let c = LuminousOpening::new(OpeningShape::VerticalCylinder, 0.3, 0.3, 0.05);
        for (cc, g) in [(0.0, 30.0), (45.0, 70.0), (300.0, 89.0)] {
            assert!(close(o.projected_area(cc, g), c.projected_area(cc, g)));
        }
    }
}
