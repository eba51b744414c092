//! Far-field photometry, pure CPU: IES LM-63 and EULUMDAT readers, the absolute photometric web,
//! luminous openings and luminance, host-lighting look-up tables, photometric solids and plots.

pub mod error;
pub mod ies;
pub mod ldt;
pub mod luminaire;
pub mod lut;
pub mod opening;
pub mod plot;
pub mod solid;
pub mod text;
pub mod web;

pub use error::{ParseError, PhotometryError};
pub use luminaire::{load, load_from_text, FileFormat, LoadOptions, Photometry};
pub use opening::{LuminousOpening, OpeningShape};
pub use web::{PhotometricType, PhotometricWeb, Symmetry};
