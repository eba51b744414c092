//! The near-field quality harness: synthetic luminaires scanned, packed, rendered on the GPU from
//! novel views in every selection mode, and compared with the exact ray-caster, by the definitions of
//! docs/quality-metrics.md (the contract; [`metrics`] implements its per-view part).
//!
//! [`evaluate`] runs one luminaire and returns a [`LuminaireReport`]; [`format_table`] prints reports
//! as the table `lumiview eval` shows; [`write_triptych`] writes a view as render | reference | error.
//!
//! - `config.rs`: [`EvalMode`], [`EvalConfig`], and the contract's per-luminaire rules (smallest
//!   feature, pixels across it, a lobe's angular feature, cameras per hemisphere);
//! - `prepare.rs`: the scan of one luminaire: captures sized by the pitch rule, held-out cameras, pack;
//! - `views.rs`: [`View`], [`framed_view`], the pitch a view needs, directions on the sphere;
//! - `render.rs`: a view's GPU render ([`render_view`]) and orthographic intensities, rendered and
//!   ray-cast;
//! - `references.rs`: what every mode is compared with: the views and orthographic directions,
//!   ray-cast;
//! - `evaluate.rs`: [`evaluate`]: the scan loaded, its references, every mode rendered and measured;
//! - `report.rs`: [`ModeReport`], [`LuminaireReport`], [`format_table`], [`write_triptych`];
//! - `verdict.rs`: [`verdict`], the contract's thresholds and comparisons on a report, and
//!   [`reconstructed_verdict`] on its reconstructed proxy's row;
//! - [`metrics`]: the per-view metrics and their aggregates;
//! - [`rays`], [`rayconv`]: ray files against their far field, and the ray-file convergence harness.

pub mod metrics;
pub mod rayconv;
pub mod rays;

mod config;
mod evaluate;
mod prepare;
mod references;
mod render;
mod report;
mod verdict;
mod views;

pub use config::{
    angular_feature_deg, cameras_per_hemisphere, feature_px, lobe_exponent, smallest_feature_m, EvalConfig, EvalMode,
    LOBE_STEP,
};
pub use evaluate::evaluate;
pub use metrics::{aggregate, compare_view, compare_view_with_margin, SetMetrics, ViewMetrics};
pub use render::render_view;
pub(crate) use render::{ortho_intensity, reference_ortho_intensity};
pub use report::{format_table, write_triptych, LuminaireReport, ModeReport};
pub use verdict::{reconstructed_verdict, verdict, Verdict, NO_THRESHOLD, TIE_FLOOR};
pub use views::{fibonacci, framed_view, View};

use crate::gpu::GpuError;

/// Errors of the harness.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The GPU side failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The synthetic or pack side failed.
    #[error(transparent)]
    Nearfield(#[from] crate::nearfield::NearfieldError),
}
