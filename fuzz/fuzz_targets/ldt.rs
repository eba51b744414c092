//! Arbitrary bytes through the EULUMDAT reader (`cargo fuzz run ldt`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| lumiview_fuzz::check(data, "fuzz.ldt"));
