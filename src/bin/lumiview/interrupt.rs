//! SIGINT and SIGTERM: remove the unfinished outputs this process is writing (its
//! `NAME.lumiview-PID-N.partial` files, [`lumiview::files::remove_temporaries`]), say so, and exit
//! with 128 + the signal number, as a shell expects. Without this a Ctrl-C during `pack` would leave
//! a temporary file of up to the pack's size behind.

/// Blocks SIGINT and SIGTERM in this thread (and so in every thread started after it) and handles
/// them on a thread of their own. Call first in `main`, before any thread is started.
#[cfg(unix)]
pub fn install() {
    // SAFETY: `sigset_t` is plain data; an all-zero value is a valid argument to `sigemptyset`,
    // which initialises it.
    let mut set: libc::sigset_t = unsafe { std::mem::zeroed() };
    // SAFETY: `set` is a valid, exclusively borrowed `sigset_t`; these calls only write to it and to
    // this thread's signal mask (the old mask is not asked for: NULL is allowed).
    let blocked = unsafe {
        libc::sigemptyset(&mut set) == 0
            && libc::sigaddset(&mut set, libc::SIGINT) == 0
            && libc::sigaddset(&mut set, libc::SIGTERM) == 0
            && libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) == 0
    };
    if !blocked {
        return; // the default actions stay: the process ends, and the next run removes stale files
    }
    let spawned = std::thread::Builder::new()
        .name("lumiview-signals".into())
        .spawn(move || loop {
            let mut sig: libc::c_int = 0;
            // SAFETY: `set` is an initialised `sigset_t` owned by this closure and `sig` a valid
            // `c_int` to write the signal number to.
            if unsafe { libc::sigwait(&set, &mut sig) } != 0 {
                continue;
            }
            let removed = lumiview::files::remove_temporaries();
            let name = if sig == libc::SIGINT { "SIGINT" } else { "SIGTERM" };
            if removed > 0 {
                eprintln!("\nlumiview: {name}: stopped; {removed} unfinished output file(s) removed");
            } else {
                eprintln!("\nlumiview: {name}: stopped");
            }
            std::process::exit(128 + sig);
        });
    if spawned.is_err() {
        // No handler thread: unblock again so that Ctrl-C still ends the process.
        // SAFETY: as above; `set` is initialised.
        unsafe {
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        }
    }
}

/// Elsewhere the default actions stay (a killed run's temporary files are removed by the next).
#[cfg(not(unix))]
pub fn install() {}
