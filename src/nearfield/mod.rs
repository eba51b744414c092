//! Near-field scans (pure CPU): ray-image sets, importers, the synthetic goniophotometer, camera
//! selection structures and the tiled `.lvpack` store. Filled in by the near-field data issue.
