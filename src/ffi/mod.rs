//! The C ABI: the only module allowed to contain `extern "C"` functions. The header
//! `include/lumiview.h` is generated from it by `scripts/gen-header` (GPU renderer issue).
