//! The manifest's JSON schema (serde): the file as written, before any check; and the conversion of
//! pinhole intrinsics to and from it.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::nearfield::error::{NearfieldError, Result};
use crate::nearfield::rayset::{Hemisphere, Intrinsics};

/// A number or a pair (`fx` = `fy` when one number is given).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub(super) enum OneOrTwo {
    One(f64),
    Two([f64; 2]),
}

impl OneOrTwo {
    fn pair(self) -> DVec2 {
        match self {
            Self::One(v) => DVec2::splat(v),
            Self::Two([a, b]) => DVec2::new(a, b),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum JsonHemisphere {
    Lower,
    Upper,
}

impl From<JsonHemisphere> for Hemisphere {
    fn from(h: JsonHemisphere) -> Self {
        match h {
            JsonHemisphere::Lower => Hemisphere::Lower,
            JsonHemisphere::Upper => Hemisphere::Upper,
        }
    }
}

impl From<Hemisphere> for JsonHemisphere {
    fn from(h: Hemisphere) -> Self {
        match h {
            Hemisphere::Lower => JsonHemisphere::Lower,
            Hemisphere::Upper => JsonHemisphere::Upper,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct JsonIntrinsics {
    width: u32,
    height: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    principal_px: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    focal_px: Option<OneOrTwo>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pixel_scale_rad: Option<OneOrTwo>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct JsonImage {
    pub(super) file: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) label: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) phi_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) theta_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) position_m: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) right: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) down: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) forward: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) hemisphere: Option<JsonHemisphere>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) exposure_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) overflow_count: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) intrinsics: Option<JsonIntrinsics>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct JsonManifest {
    pub(super) format: String,
    pub(super) version: u32,
    pub(super) radius_m: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) centre_m: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) hemisphere: Option<JsonHemisphere>,
    pub(super) intrinsics: JsonIntrinsics,
    pub(super) images: Vec<JsonImage>,
}

pub(super) fn dvec3(a: [f64; 3]) -> DVec3 {
    DVec3::new(a[0], a[1], a[2])
}

/// Converts JSON intrinsics; `what` names them in errors.
pub(super) fn intrinsics_from_json(j: &JsonIntrinsics, what: &str) -> Result<Intrinsics> {
    let focal = match (j.focal_px, j.pixel_scale_rad) {
        (Some(f), None) => f.pair(),
        (None, Some(s)) => {
            let s = s.pair();
            if !(s.x.is_finite() && s.y.is_finite() && s.x > 0.0 && s.y > 0.0) {
                return Err(NearfieldError::invalid(
                    format!("{what}: pixel_scale_rad"),
                    format!("({}, {}) must be finite and > 0", s.x, s.y),
                ));
            }
            DVec2::ONE / s
        }
        (Some(_), Some(_)) => {
            return Err(NearfieldError::invalid(
                format!("{what}: intrinsics"),
                "give focal_px or pixel_scale_rad, not both",
            ))
        }
        (None, None) => {
            return Err(NearfieldError::invalid(
                format!("{what}: intrinsics"),
                "focal_px or pixel_scale_rad is required",
            ))
        }
    };
    let principal = j.principal_px.map_or(
        DVec2::new(f64::from(j.width) / 2.0, f64::from(j.height) / 2.0),
        |[x, y]| DVec2::new(x, y),
    );
    let k = Intrinsics {
        width: j.width,
        height: j.height,
        principal_px: principal,
        focal_px: focal,
    };
    k.validate(what)?;
    Ok(k)
}

pub(super) fn intrinsics_to_json(k: &Intrinsics) -> JsonIntrinsics {
    JsonIntrinsics {
        width: k.width,
        height: k.height,
        principal_px: Some([k.principal_px.x, k.principal_px.y]),
        focal_px: Some(OneOrTwo::Two([k.focal_px.x, k.focal_px.y])),
        pixel_scale_rad: None,
    }
}
