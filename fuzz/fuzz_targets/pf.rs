//! Arbitrary bytes read as a TechnoTeam `.pf` / `.pcf` luminance image and as a PFM
//! (`cargo fuzz run pf`): the readers never panic, and never allocate a pixel buffer larger than
//! the input holds. A decoded image has exactly width × height values.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use lumiview::nearfield::images::{parse_pf, parse_pf_header, parse_pfm, MAX_DIMENSION};
use lumiview::nearfield::LuminanceImage;

fn check(img: &LuminanceImage, input_len: usize, channels: usize) {
    assert!(img.width >= 1 && img.width <= MAX_DIMENSION && img.height >= 1 && img.height <= MAX_DIMENSION);
    let n = img.width as usize * img.height as usize;
    assert_eq!(img.data.len(), n, "pixel count");
    assert!(n * 4 * channels <= input_len, "more pixels than the input holds");
}

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.pf");
    if let Ok(h) = parse_pf_header(data, data.len() as u64, path) {
        assert!(h.header_len <= data.len());
        let img = parse_pf(data, path).expect("a header that checks out decodes");
        check(&img, data.len(), if h.colour { 3 } else { 1 });
    } else {
        assert!(parse_pf(data, path).is_err());
    }
    if let Ok(img) = parse_pfm(data, Path::new("fuzz.pfm")) {
        check(&img, data.len(), 1);
    }
});
