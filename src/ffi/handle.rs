//! Handles that cannot cross contexts. A `lumi_luminaire`, `lumi_instance`, `lumi_target` or
//! `lumi_scene` is a 64-bit value: the context's tag (bits 40–63, unique per context created in the
//! process, 1 … 2²⁴ − 1, then reused), the kind (bits 36–39: 1 luminaire, 2 instance, 3 target,
//! 4 scene) and a serial (bits 0–35) that a context never hands out twice, so a destroyed object's
//! handle stays invalid. 0 is never a handle. A handle of another context, of another kind, or of
//! an object destroyed is `LUMI_STATUS_INVALID_ARGUMENT` naming the argument.

use std::sync::atomic::{AtomicU64, Ordering};

use super::FfiError;

/// What a handle names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// `lumi_luminaire`.
    Luminaire = 1,
    /// `lumi_instance`.
    Instance = 2,
    /// `lumi_target`.
    Target = 3,
    /// `lumi_scene`.
    Scene = 4,
}

impl Kind {
    fn name(k: u64) -> Option<&'static str> {
        match k {
            1 => Some("luminaire"),
            2 => Some("instance"),
            3 => Some("target"),
            4 => Some("scene"),
            _ => None,
        }
    }
}

const SERIAL_BITS: u32 = 36;
const KIND_BITS: u32 = 4;
const TAG_SHIFT: u32 = SERIAL_BITS + KIND_BITS;
const SERIAL_MASK: u64 = (1 << SERIAL_BITS) - 1;
const TAG_MAX: u64 = (1 << (64 - TAG_SHIFT)) - 1;

/// A new context's tag.
pub(crate) fn new_context_tag() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    NEXT.fetch_add(1, Ordering::Relaxed) % TAG_MAX + 1
}

/// The handle of object `serial` (≥ 1) of `kind` in the context tagged `tag`.
pub(crate) fn encode(tag: u64, kind: Kind, serial: u64) -> u64 {
    (tag << TAG_SHIFT) | ((kind as u64) << SERIAL_BITS) | (serial & SERIAL_MASK)
}

/// The serial of `handle` (argument `arg`) if it is a `kind` handle of the context tagged `tag`.
///
/// Errors: `LUMI_STATUS_INVALID_ARGUMENT` naming `arg`: 0, not a lumiview handle, another kind, or
/// another context's.
pub(crate) fn decode(tag: u64, kind: Kind, handle: u64, arg: &str) -> Result<u64, FfiError> {
    let want = Kind::name(kind as u64).unwrap_or("object");
    let a = |n: &str| {
        if n.starts_with(['a', 'e', 'i', 'o', 'u']) {
            "an"
        } else {
            "a"
        }
    };
    if handle == 0 {
        return Err(FfiError::invalid(arg, format!("0 is not {} {want} handle", a(want))));
    }
    let (t, k, serial) = (handle >> TAG_SHIFT, (handle >> SERIAL_BITS) & 0xF, handle & SERIAL_MASK);
    match Kind::name(k) {
        None => Err(FfiError::invalid(arg, format!("{handle:#x} is not a lumiview handle"))),
        Some(is) if k != kind as u64 => Err(FfiError::invalid(
            arg,
            format!("{handle:#x} is {} {is} handle, not {} {want} handle", a(is), a(want)),
        )),
        _ if t != tag => Err(FfiError::invalid(
            arg,
            format!("{want} handle {handle:#x} belongs to another context"),
        )),
        _ => Ok(serial),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_name_their_context_and_kind() {
        let (a, b) = (new_context_tag(), new_context_tag());
        assert_ne!(a, b);
        let h = encode(a, Kind::Luminaire, 7);
        assert_eq!(decode(a, Kind::Luminaire, h, "luminaire").unwrap(), 7);
        let e = decode(b, Kind::Luminaire, h, "luminaire").unwrap_err();
        assert!(e.message.contains("another context"), "{}", e.message);
        let e = decode(a, Kind::Instance, h, "instance").unwrap_err();
        assert!(
            e.message.contains("is a luminaire handle, not an instance handle"),
            "{}",
            e.message
        );
        assert!(decode(a, Kind::Target, 0, "target").is_err());
        let s = encode(a, Kind::Scene, 3);
        assert_eq!(decode(a, Kind::Scene, s, "scene").unwrap(), 3);
        let e = decode(a, Kind::Target, s, "target").unwrap_err();
        assert!(
            e.message.contains("is a scene handle, not a target handle"),
            "{}",
            e.message
        );
        assert!(decode(a, Kind::Target, 5, "target")
            .unwrap_err()
            .message
            .contains("not a lumiview handle"));
    }
}
