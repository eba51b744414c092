//! Camera selection (`lumiview::nearfield::select`): the spherical Delaunay triangulation (empty
//! circumcaps, Euler, closed and tiling the sphere), merged pole duplicates, holes over unmeasured
//! regions, cocircular layouts, a brute-force cross-check of all three modes on ≥ 20,000 random
//! directions, conservative cell lists under an fp32 cell computation, continuity of the Continuous
//! weights (and the jumps of Nearest), exactness for linear data, the 56,000-camera build, and bad input.
//!
//! One test binary (`nearfield_select`, CPU only), its parts by concept:
//! - `common.rs`: what every part uses: camera sets from layouts or directions, random directions,
//!   a triangle's corners and edge values;
//! - `triangulation.rs`: the build: structure and the Delaunay property, poles, holes, folded caps,
//!   cocircular grids, and the input it refuses;
//! - `queries.rs`: the three modes' weights against brute force, continuity, exactness for linear
//!   data, and the 56,000-camera build;
//! - `cells.rs`: the cell lists (conservative at borders and for an fp32 cell) and the cells a view keeps.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod cells;
mod common;
mod queries;
mod triangulation;
