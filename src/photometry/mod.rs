//! Far-field photometry, pure CPU: IES LM-63 and EULUMDAT readers, the absolute photometric web,
//! luminous openings and luminance, host-lighting look-up tables, photometric solids, polar plots,
//! illuminance on a floor plane with its isolux lines, and the triangles and lines the renderer
//! draws for openings, solids and housings (`meshes`).
//!
//! ```
//! use lumiview::photometry::{load_from_text, LoadOptions};
//!
//! // A rotationally symmetric LM-63-2002 file, 0.2 m square opening, multiplier 2.
//! let ies = "IESNA:LM-63-2002\n[TEST] doc\nTILT=NONE\n1 -1 2.0 3 1 1 2 0.2 0.2 0\n1 1 10\n0 45 90\n0\n100 50 0\n";
//! let ph = load_from_text(ies, "doc.ies", &LoadOptions::default())?;
//! assert_eq!(ph.intensity(0.0, 0.0), 200.0); // cd, nadir
//! assert_eq!(ph.intensity(123.0, 22.5), 150.0); // bilinear between the 0° and 45° rows
//! assert_eq!(ph.intensity(0.0, 120.0), 0.0); // outside the measured 0–90° range
//! let l = ph.luminance(0.0, 0.0).unwrap(); // cd/m² of the opening seen from below
//! assert!((l - 200.0 / 0.04).abs() < 1e-9);
//! assert!(ph.flux_lm() > 0.0);
//! # Ok::<(), lumiview::photometry::PhotometryError>(())
//! ```

pub mod contour;
pub mod convert;
pub mod error;
pub mod ies;
pub mod isolux;
pub mod ldt;
pub mod luminaire;
pub mod lut;
pub mod meshes;
pub mod opening;
pub mod plot;
pub mod solid;
pub mod summary;
pub mod text;
pub mod web;

pub use error::{ParseError, PhotometryError};
pub use luminaire::{load, load_from_text, FileFormat, LoadOptions, Photometry};
pub use opening::{LuminousOpening, OpeningShape};
pub use summary::{Peak, Summary};
pub use web::{PhotometricType, PhotometricWeb, Symmetry};
