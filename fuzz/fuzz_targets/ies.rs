//! Arbitrary bytes through the IES LM-63 reader (`cargo fuzz run ies`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| lumiview_fuzz::check(data, "fuzz.ies"));
