//! The allocator between the stages of a long computation: memory freed by one stage is handed back
//! to the system before the next begins.
//!
//! glibc's allocator keeps what a program frees for its own reuse: after a few large blocks (a
//! full-size capture image is 5 MB) are freed it raises its thresholds, serves them from its arenas
//! and keeps up to twice the largest one free in each arena. Across the proxy reconstruction's
//! stages (masks, carving, meshing, refining) that held 13–30 MB resident beyond what the stages
//! allocated, which put its peak above the pack's own (docs/proxy.md). [`return_freed_memory`]
//! returns the free pages of every arena (`malloc_trim(0)`); elsewhere it does nothing.

/// Hands the memory freed so far back to the system (glibc: `malloc_trim(0)`; other C libraries and
/// systems: nothing). Cheap next to a stage of seconds; it never frees what is still in use.
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free memory inside the allocator's arenas; it takes the
    // arenas' locks and is safe to call from any thread at any time.
    unsafe {
        libc::malloc_trim(0);
    }
}
