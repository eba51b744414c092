//! SIGINT and SIGTERM: remove the unfinished outputs this process is writing (its
//! `NAME.lumiview-PID-UNIQUE.partial` files, [`lumiview::files::remove_temporaries`]), say so, and end
//! as the signal would have ended the process (a shell loop or script sees a death by SIGINT and
//! stops). Without this a Ctrl-C during `pack` would leave a temporary file of up to the pack's size
//! behind. A signal the process was started to ignore (`nohup`, a background job of a script) stays
//! ignored.

/// Blocks SIGINT and SIGTERM in this thread (and so in every thread started after it) and handles
/// them on a thread of their own. Call in `main` before any other thread is started.
#[cfg(unix)]
pub fn install() {
    // SAFETY: `sigset_t` and `sigaction` are plain C data; all-zero values are valid arguments to
    // `sigemptyset` (which initialises the set) and to `sigaction` as the old action to fill in.
    let (mut set, mut old): (libc::sigset_t, libc::sigaction) = unsafe { (std::mem::zeroed(), std::mem::zeroed()) };
    // SAFETY: `set` is a valid, exclusively borrowed `sigset_t`.
    unsafe {
        libc::sigemptyset(&mut set);
    }
    let mut handled = 0;
    for sig in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: a NULL new action only reads the current one into `old`, a valid `sigaction`.
        let ignored =
            unsafe { libc::sigaction(sig, std::ptr::null(), &mut old) } == 0 && old.sa_sigaction == libc::SIG_IGN;
        if !ignored {
            // SAFETY: `set` was initialised by `sigemptyset`; `sig` is a valid signal number.
            unsafe {
                libc::sigaddset(&mut set, sig);
            }
            handled += 1;
        }
    }
    // SAFETY: `set` is initialised; the old mask is not asked for (NULL is allowed).
    if handled == 0 || unsafe { libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) } != 0 {
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
            // End by the signal itself: default action, unblocked in this thread, raised again.
            // SAFETY: `one` is initialised by `sigemptyset` before use; `signal`, `pthread_sigmask`
            // and `raise` take a valid signal number and that set; nothing else is touched.
            unsafe {
                let mut one: libc::sigset_t = std::mem::zeroed();
                libc::sigemptyset(&mut one);
                libc::sigaddset(&mut one, sig);
                libc::signal(sig, libc::SIG_DFL);
                libc::pthread_sigmask(libc::SIG_UNBLOCK, &one, std::ptr::null_mut());
                libc::raise(sig);
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
