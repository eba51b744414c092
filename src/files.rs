//! Files as every reader and writer of lumiview handles them (pure CPU, std only):
//!
//! - **Reading** ([`open_regular`], [`read_regular`]): only regular files are opened (a FIFO, a
//!   device such as `/dev/zero`, a socket or a directory is refused before it is opened, so nothing
//!   blocks or reads forever), and a reader's size limit is checked before anything is allocated.
//!   A buffer that cannot be allocated is an [`std::io::ErrorKind::OutOfMemory`] error, never an
//!   abort. Messages do not repeat the path: callers name the file.
//! - **Writing** ([`TempOutput`]): an output is written under a unique temporary name beside it
//!   (`NAME.lumiview-PID-UNIQUE.partial`) and renamed into place when complete, so a failed, killed
//!   or concurrent run never leaves a half-written file under the output's name and two writers of
//!   one output never mix their bytes (the last complete one wins). The writer holds an exclusive
//!   lock on its temporary file until it is renamed or removed. It is removed when the writer fails
//!   or is dropped, and when the process is interrupted: a program that handles SIGINT/SIGTERM calls
//!   [`remove_temporaries`] (the `lumiview` CLI does). Temporary files of the same output left by a
//!   run that was killed outright (SIGKILL, power loss) hold no lock any more; the next writer of
//!   that output removes them ([`TempOutput::create`] returns their names). A file still locked
//!   (another live writer, in any process, container or host sharing the folder) is never touched.
//! - **Inputs are never replaced** ([`ensure_not_input`]): an output that is the same file as an
//!   input (or a file an input refers to: a manifest's images) is an error before anything is
//!   written.

use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

/// A reader's size limit was exceeded, or the path is not a regular file.
fn refused(message: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message)
}

/// What a non-regular file is, for messages ("a FIFO (named pipe)").
fn kind_name(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

/// Opens `path` for reading if it is a regular file of at most `max_bytes` bytes (`what` names the
/// kind of file in the message, e.g. "an IES or EULUMDAT file"). Returns the file and its length.
///
/// Errors ([`std::io::ErrorKind::InvalidInput`], before the file is opened): a FIFO, device,
/// socket or directory; a file longer than `max_bytes`. Otherwise the errors of opening it.
pub fn open_regular(path: &Path, max_bytes: u64, what: &str) -> std::io::Result<(File, u64)> {
    // Metadata first: opening a FIFO blocks until someone writes to it.
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(refused(format!("{}, not a regular file; refused", kind_name(&meta))));
    }
    if meta.len() > max_bytes {
        return Err(refused(format!(
            "{} bytes is more than the {max_bytes} bytes {what} may have (docs/formats.md, \"Limits\"); refused \
             before reading",
            meta.len()
        )));
    }
    let file = File::open(path)?;
    // The path may have been replaced between the two calls.
    let meta = file.metadata()?;
    if !meta.is_file() || meta.len() > max_bytes {
        return Err(refused(format!(
            "{} changed while it was opened; refused",
            path.display()
        )));
    }
    Ok((file, meta.len()))
}

/// An empty vector with room for `n` items, or an [`std::io::ErrorKind::OutOfMemory`] error
/// naming `what` when the memory cannot be had (for buffers as large as a file: never an abort).
pub fn try_vec<T>(n: usize, what: &str) -> std::io::Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::OutOfMemory,
            format!(
                "cannot allocate {} bytes for {what}",
                n.saturating_mul(std::mem::size_of::<T>())
            ),
        )
    })?;
    Ok(v)
}

/// Reads all of `path` if it is a regular file of at most `max_bytes` bytes ([`open_regular`]). At
/// most `max_bytes` are read even if the file grows meanwhile.
///
/// Errors: those of [`open_regular`]; [`std::io::ErrorKind::OutOfMemory`] when the buffer cannot
/// be allocated; a file that grew past the limit while it was read.
pub fn read_regular(path: &Path, max_bytes: u64, what: &str) -> std::io::Result<Vec<u8>> {
    let (file, len) = open_regular(path, max_bytes, what)?;
    let mut bytes = try_vec(len as usize, "reading it")?;
    file.take(max_bytes.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(refused(format!(
            "the file grew past the {max_bytes} bytes {what} may have while it was read"
        )));
    }
    Ok(bytes)
}

/// Whether `a` and `b` name the same existing file (same device and inode on Unix; same canonical
/// path elsewhere). `false` when either does not exist.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}

/// Refuses an `output` that is one of `inputs` (the same file under any name).
///
/// Errors: a message naming the output and the input it would replace.
pub fn ensure_not_input<'a>(output: &Path, inputs: impl IntoIterator<Item = &'a Path>) -> Result<(), String> {
    if !output.exists() {
        return Ok(());
    }
    for input in inputs {
        if same_file(output, input) {
            return Err(if output == input {
                format!(
                    "{}: the output is an input of this run; write it elsewhere",
                    output.display()
                )
            } else {
                format!(
                    "{}: the output is the same file as the input {}; write it elsewhere",
                    output.display(),
                    input.display()
                )
            });
        }
    }
    Ok(())
}

/// Temporary files of this process not yet renamed or removed (for [`remove_temporaries`]).
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file a [`TempOutput`] of this process holds and keeps the registry
/// locked from then on, so no thread of the process registers (and so creates) another one: call
/// it when the process is interrupted, just before it ends (the `lumiview` CLI does on SIGINT and
/// SIGTERM). Returns how many were removed.
pub fn remove_temporaries() -> usize {
    let live = LIVE.lock().unwrap_or_else(PoisonError::into_inner);
    let n = live.iter().filter(|p| std::fs::remove_file(p).is_ok()).count();
    // Held until the process ends: a writer that tries to create a temporary file now waits.
    std::mem::forget(live);
    n
}

fn register(p: &Path) {
    LIVE.lock()
        .unwrap_or_else(PoisonError::into_inner)
        .push(p.to_path_buf());
}

fn unregister(p: &Path) {
    LIVE.lock().unwrap_or_else(PoisonError::into_inner).retain(|q| q != p);
}

/// The marker between an output's name and a temporary file's PID.
const TEMP_MARK: &str = ".lumiview-";
/// A temporary file's suffix.
const TEMP_SUFFIX: &str = ".partial";

/// An output being written: a uniquely named temporary file beside it, locked while it exists,
/// renamed into place by [`TempOutput::commit`], removed if dropped before that.
#[derive(Debug)]
pub struct TempOutput {
    target: PathBuf,
    temp: PathBuf,
    file: Option<File>,
    /// A second handle of the same open file, holding the exclusive lock until the file is
    /// renamed or removed (the writer may close its handle before that).
    lock: Option<File>,
}

impl TempOutput {
    /// Creates the temporary file for `target` (`TARGET.lumiview-PID-UNIQUE.partial`, created
    /// new, never an existing file) and locks it. First removes the temporary files of `target`
    /// that no writer holds any more (left by a killed run), and returns their names (a caller may
    /// report them) with the new output.
    ///
    /// Errors: `target` without a file name; the file cannot be created.
    pub fn create(target: &Path) -> std::io::Result<(TempOutput, Vec<PathBuf>)> {
        static NONCE: AtomicU64 = AtomicU64::new(0);
        let name = target
            .file_name()
            .ok_or_else(|| refused(format!("{} has no file name", target.display())))?
            .to_string_lossy()
            .into_owned();
        let stale = remove_stale(target, &name);
        let pid = std::process::id();
        let clock = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        loop {
            let n = NONCE.fetch_add(1, Ordering::Relaxed);
            let temp = target.with_file_name(format!("{name}{TEMP_MARK}{pid}-{clock:08x}{n}{TEMP_SUFFIX}"));
            // Registered before it exists: an interrupt between the two still removes it.
            register(&temp);
            let opened = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create_new(true)
                .open(&temp);
            let file = match opened {
                Ok(f) => f,
                Err(e) => {
                    unregister(&temp);
                    if e.kind() == std::io::ErrorKind::AlreadyExists {
                        continue;
                    }
                    return Err(e);
                }
            };
            // Owned from here: an error below removes the file again.
            let mut out = TempOutput {
                target: target.to_path_buf(),
                temp,
                lock: None,
                file: None,
            };
            // A file system without locks (some network mounts) still gets its temporary file:
            // only the removal of stale files relies on the lock.
            let lock = file.try_clone()?;
            let _ = lock.try_lock();
            out.file = Some(file);
            out.lock = Some(lock);
            return Ok((out, stale));
        }
    }

    /// The temporary file's path.
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// The open temporary file (read + write). `None` after [`TempOutput::take_file`].
    pub fn file(&mut self) -> Option<&mut File> {
        self.file.as_mut()
    }

    /// Takes the open file (the caller writes and closes it; the name and the lock stay with
    /// `self`).
    pub fn take_file(&mut self) -> Option<File> {
        self.file.take()
    }

    /// Closes the file and renames it to the target (atomically replacing an older one).
    ///
    /// Errors: the rename fails (the temporary file is then removed).
    pub fn commit(mut self) -> std::io::Result<()> {
        if let Some(mut f) = self.file.take() {
            f.flush()?;
        }
        let r = std::fs::rename(&self.temp, &self.target);
        if r.is_ok() {
            unregister(&self.temp);
        }
        r
    }
}

impl Drop for TempOutput {
    fn drop(&mut self) {
        self.file.take();
        let live = LIVE.lock().unwrap_or_else(PoisonError::into_inner).contains(&self.temp);
        if live {
            let _ = std::fs::remove_file(&self.temp);
            unregister(&self.temp);
        }
        // The lock goes last: nobody may take the file for stale while it is still ours.
        self.lock.take();
    }
}

/// Whether process `pid` is visibly alive (Linux: `/proc/PID` exists; `false` where this cannot
/// be seen: another PID namespace, `hidepid`, no `/proc`).
fn process_alive(pid: u32) -> bool {
    pid == std::process::id() || Path::new("/proc").join(pid.to_string()).exists()
}

/// Removes `TARGET.lumiview-*.partial` files that no writer holds (their lock can be taken: the
/// process that made them is gone); returns their paths. A file that cannot be opened or locked is
/// left alone.
fn remove_stale(target: &Path, name: &str) -> Vec<PathBuf> {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    let prefix = format!("{name}{TEMP_MARK}");
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let file_name = e.file_name();
        let Some(f) = file_name.to_str() else { continue };
        if !(f.starts_with(&prefix) && f.ends_with(TEMP_SUFFIX)) {
            continue;
        }
        let path = e.path();
        if LIVE.lock().unwrap_or_else(PoisonError::into_inner).contains(&path) {
            continue; // this process's own
        }
        // A writer's process that is visibly alive keeps its file even before it has locked it
        // (the moment between creating and locking); otherwise the lock decides.
        let pid = f[prefix.len()..].split('-').next().and_then(|p| p.parse::<u32>().ok());
        if pid.is_some_and(process_alive) {
            continue;
        }
        let Ok(file) = std::fs::File::open(&path) else {
            continue;
        };
        if file.try_lock().is_ok() && std::fs::remove_file(&path).is_ok() {
            removed.push(path);
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("lumiview-files-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn limits_are_checked_before_reading() {
        let d = dir("limits");
        let p = d.join("a.txt");
        std::fs::write(&p, b"12345").unwrap();
        assert_eq!(read_regular(&p, 5, "a test file").unwrap(), b"12345");
        let e = read_regular(&p, 4, "a test file").unwrap_err();
        assert!(
            e.to_string().contains("more than the 4 bytes a test file may have"),
            "{e}"
        );
        let e = read_regular(&d, 100, "a test file").unwrap_err();
        assert!(e.to_string().contains("a directory, not a regular file"), "{e}");
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn devices_are_refused() {
        let e = read_regular(Path::new("/dev/zero"), 1 << 20, "a test file").unwrap_err();
        assert!(e.to_string().contains("a device"), "{e}");
    }

    #[test]
    fn temp_outputs_commit_or_vanish_and_stale_ones_are_removed() {
        let d = dir("temp");
        let target = d.join("out.bin");
        std::fs::write(&target, b"old").unwrap();
        let (mut t, _) = TempOutput::create(&target).unwrap();
        t.file().unwrap().write_all(b"new").unwrap();
        let temp = t.path().to_path_buf();
        drop(t);
        assert!(!temp.exists());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        let (mut a, _) = TempOutput::create(&target).unwrap();
        let (mut b, _) = TempOutput::create(&target).unwrap();
        assert_ne!(a.path(), b.path());
        a.file().unwrap().write_all(b"a").unwrap();
        b.file().unwrap().write_all(b"b").unwrap();
        b.commit().unwrap();
        a.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"a");
        // A left-over file nobody holds is removed; one that is locked (a live writer) is not.
        let stale = d.join(format!("out.bin{TEMP_MARK}4294967295-1{TEMP_SUFFIX}"));
        std::fs::write(&stale, b"x").unwrap();
        let held = d.join(format!("out.bin{TEMP_MARK}4294967294-1{TEMP_SUFFIX}"));
        std::fs::write(&held, b"x").unwrap();
        let holder = std::fs::File::open(&held).unwrap();
        holder.lock().unwrap();
        let (t, removed) = TempOutput::create(&target).unwrap();
        assert_eq!(removed, vec![stale.clone()]);
        assert!(!stale.exists() && held.exists());
        // Our own live temporary file is not stale to a second writer in this process.
        let (t2, removed) = TempOutput::create(&target).unwrap();
        assert!(removed.is_empty() && t.path().exists());
        drop((t, t2));
        drop(holder);
    }

    #[test]
    fn an_output_that_is_an_input_is_refused() {
        let d = dir("same");
        let a = d.join("a");
        std::fs::write(&a, b"x").unwrap();
        let alias = d.join(".").join("a");
        assert!(ensure_not_input(&alias, [a.as_path()]).is_err());
        assert!(ensure_not_input(&d.join("b"), [a.as_path()]).is_ok());
    }
}
