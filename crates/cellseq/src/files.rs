//! Files: reading text and safe writes — every file cellseq writes goes through this module.
//!
//! [`write_file`] (and [`write_atomic`], which calls it) writes a whole file so that a
//! reader never sees half of it and nothing but the target is ever touched:
//!
//! - **Regular file or new name**: the bytes go to a temporary file in the target's directory,
//!   named `.NAME.RANDOM.tmp` (128 random bits from the operating system's generator, so the
//!   name cannot be guessed and planted in advance), created exclusively (`O_CREAT | O_EXCL |
//!   O_NOFOLLOW`: an existing file or symbolic link at that name makes creation fail rather than
//!   being followed). The file is written, flushed to disk (`fsync`), renamed over the target and
//!   the directory is flushed too where the system allows it. An existing target keeps its
//!   read, write and execute permission bits (set-user-id and similar bits are dropped).
//! - **Symbolic link at the target**: the link itself is replaced by the new file; it is never
//!   written through — unless it leads to a FIFO or a character device (`-o /dev/stdout`,
//!   `/dev/fd/3`), which is written directly as below. This is the behaviour of `sed -i`
//!   without `--follow-symlinks`: a link planted at an output name can at worst be replaced,
//!   never make cellseq overwrite what it points to.
//! - **FIFO or character device** (`/dev/null`, a named pipe, a terminal): opened for writing
//!   without creating or truncating anything and written directly; the node stays what it was.
//! - **Directory, block device or socket**: refused with an error naming the target.
//!
//! On every error path (a failed or short write, `ENOSPC`, a failed `fsync` or rename) the
//! temporary file is removed. While a temporary file exists its path is held in a small registry;
//! the first write installs a handler for SIGINT, SIGTERM and SIGHUP that removes every
//! registered temporary file and ends the process with status 128 + the signal number.
//!
//! [`open_append`] opens a table for appending without following a symbolic link, and
//! [`ensure_not_input`] refuses an output that is one of the command's inputs.
//!
//! Testing hook: when the environment variable `CELLSEQ_TEST_PAUSE_WRITE` names a file, a write
//! of at least 2 bytes stops halfway, creates that file and sleeps for a minute, so a test can
//! signal the process while a temporary file exists.

use crate::error::{Error, Result};
use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::{Mutex, Once};

/// Largest input file read: 4 GiB (a matrix file of the default 20 000-node limit holds about
/// 2 GB of text). A longer input (an endless pipe, `/dev/zero`) is refused, naming the file,
/// once this much has been read.
pub const MAX_INPUT_BYTES: u64 = 1 << 32;

/// Reads a whole file as UTF-8 text: refused, naming the file, when it is longer than
/// [`MAX_INPUT_BYTES`], holds a NUL byte (no text format here has one; the line is named, and
/// reading stops there, so `/dev/zero` is refused at once) or is not UTF-8.
pub fn read_text(path: &Path) -> Result<String> {
    let file = path.display().to_string();
    let bytes = read_capped(path, true)?;
    String::from_utf8(bytes).map_err(|e| {
        Error::invalid(
            &file,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })
}

/// Reads a whole file as bytes (a DXF may be binary): refused, naming the file, when it is
/// longer than [`MAX_INPUT_BYTES`].
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    read_capped(path, false)
}

/// Reads `path` in chunks up to [`MAX_INPUT_BYTES`] (a regular file longer than that is
/// refused before reading); with `text`, stops at the first NUL byte; without, refuses an
/// input that starts with one (no format read here does: a link to `/dev/zero`).
fn read_capped(path: &Path, text: bool) -> Result<Vec<u8>> {
    use std::io::Read;
    let file = path.display().to_string();
    let mut f = File::open(path).map_err(|e| Error::io(&file, e))?;
    let too_long = || {
        Error::invalid(
            &file,
            format!("longer than {MAX_INPUT_BYTES} bytes, the most an input may hold"),
        )
    };
    let size = f.metadata().ok().filter(|m| m.is_file()).map(|m| m.len());
    if size.is_some_and(|s| s > MAX_INPUT_BYTES) {
        return Err(too_long());
    }
    let mut out = Vec::with_capacity(size.unwrap_or(0) as usize);
    let mut chunk = vec![0u8; 1 << 20];
    loop {
        let n = match f.read(&mut chunk) {
            Ok(0) => return Ok(out),
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(Error::io(&file, e)),
        };
        if text && let Some(at) = chunk[..n].iter().position(|&b| b == 0) {
            out.extend_from_slice(&chunk[..at]);
            let line = out.iter().filter(|&&b| b == b'\n').count() + 1;
            return Err(Error::parse(
                &file,
                line,
                format!(
                    "a NUL byte at byte {}: not a text file",
                    out.len() as u64 + 1
                ),
            ));
        }
        if !text && out.is_empty() && chunk[0] == 0 {
            return Err(Error::invalid(
                &file,
                "starts with a NUL byte: not a drawing or program",
            ));
        }
        if out.len() as u64 + n as u64 > MAX_INPUT_BYTES {
            return Err(too_long());
        }
        out.extend_from_slice(&chunk[..n]);
    }
}

/// Writes a whole file safely: through an exclusively created temporary sibling with a random
/// name, `fsync` and a rename, so readers never see half a file and no planted link is followed;
/// FIFOs and character devices are written directly, directories and other special files are
/// refused (see the module documentation for every rule).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_file(path, bytes)
}

/// Temporary files that exist right now (removed by the signal handler).
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static HANDLER: Once = Once::new();

fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Installs (once) the handler that removes live temporary files on SIGINT/SIGTERM/SIGHUP.
fn install_handler() {
    HANDLER.call_once(|| {
        #[cfg(unix)]
        {
            use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
            // Without a handler a signal still ends the process; only the clean-up is lost.
            if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])
            {
                let spawned = std::thread::Builder::new()
                    .name("cellseq-signals".into())
                    .spawn(move || {
                        if let Some(sig) = signals.forever().next() {
                            // Holding the lock keeps any new temporary file from appearing.
                            let paths = live();
                            for p in paths.iter() {
                                let _ = std::fs::remove_file(p);
                            }
                            std::process::exit(128 + sig);
                        }
                    });
                drop(spawned);
            }
        }
    });
}

/// A temporary file registered for removal on a signal; removed on drop unless persisted.
struct Temp {
    path: PathBuf,
    armed: bool,
}

impl Temp {
    fn register(path: PathBuf) -> Temp {
        install_handler();
        live().push(path.clone());
        Temp { path, armed: true }
    }
    /// Forgets the path (it has been renamed away).
    fn disarm(&mut self) {
        self.armed = false;
        live().retain(|p| p != &self.path);
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        if self.armed {
            let _ = std::fs::remove_file(&self.path);
            live().retain(|p| p != &self.path);
        }
    }
}

/// What is at the target path, and so how it is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    /// Nothing, a regular file or a symbolic link that leads to neither a FIFO nor a
    /// character device: write a temporary file and rename it over the name. `Some(mode)`
    /// keeps an existing regular file's permission bits.
    Replace(Option<u32>),
    /// A FIFO or a character device (possibly through a link): write into it directly.
    Direct,
}

#[cfg(unix)]
fn is_stream(ft: &std::fs::FileType) -> bool {
    use std::os::unix::fs::FileTypeExt;
    ft.is_fifo() || ft.is_char_device()
}

#[cfg(not(unix))]
fn is_stream(_ft: &std::fs::FileType) -> bool {
    false
}

/// Refuses directories, block devices and sockets; says how anything else is written.
fn classify(path: &Path) -> Result<Target> {
    let file = path.display().to_string();
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Target::Replace(None)),
        Err(e) => return Err(Error::io(&file, e)),
    };
    let ft = meta.file_type();
    if ft.is_symlink() {
        return Ok(match std::fs::metadata(path) {
            Ok(m) if is_stream(&m.file_type()) => Target::Direct,
            _ => Target::Replace(None),
        });
    }
    if ft.is_dir() {
        return Err(Error::invalid(
            &file,
            "is a directory; give a file name to write",
        ));
    }
    if ft.is_file() {
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            return Ok(Target::Replace(Some(meta.permissions().mode() & 0o777)));
        }
        #[cfg(not(unix))]
        return Ok(Target::Replace(None));
    }
    if is_stream(&ft) {
        return Ok(Target::Direct);
    }
    Err(Error::invalid(
        &file,
        "is a block device, socket or other special file; cellseq will not write onto it",
    ))
}

/// 128 random bits as hex, from the thread generator (seeded by the operating system).
fn random_suffix() -> String {
    use rand::RngExt;
    let bits: u128 = rand::rng().random();
    format!("{bits:032x}")
}

/// The temporary sibling of `path`: `.NAME.RANDOM.tmp` (NAME cut to 100 bytes).
fn temp_path(dir: &Path, name: &str) -> PathBuf {
    let mut cut = name.len().min(100);
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    dir.join(format!(".{}.{}.tmp", &name[..cut], random_suffix()))
}

/// Creates a new file exclusively, never following a link, with mode 0666 less the umask.
fn create_exclusive(path: &Path) -> io::Result<File> {
    let mut o = OpenOptions::new();
    o.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.mode(0o666)
            .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC);
    }
    o.open(path)
}

/// Pauses a write halfway when the testing hook asks for it (see the module documentation).
fn test_pause() {
    if let Some(marker) = std::env::var_os("CELLSEQ_TEST_PAUSE_WRITE") {
        let _ = std::fs::write(marker, b"paused\n");
        std::thread::sleep(std::time::Duration::from_secs(60));
    }
}

/// Writes `bytes` to `path` safely (see the module documentation).
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |w| {
        let half = bytes.len() / 2;
        if half > 0 && std::env::var_os("CELLSEQ_TEST_PAUSE_WRITE").is_some() {
            w.write_all(&bytes[..half])?;
            w.flush()?;
            test_pause();
            return w.write_all(&bytes[half..]);
        }
        w.write_all(bytes)
    })
}

/// Writes the output of `fill` to `path` safely (see the module documentation). An error from
/// `fill` removes the temporary file and leaves the target as it was.
pub fn write_with<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let file = path.display().to_string();
    match classify(path)? {
        Target::Direct => write_direct(path, fill).map_err(|e| Error::io(&file, e)),
        Target::Replace(mode) => write_replace(path, mode, fill),
    }
}

/// Writes into an existing FIFO or character device without creating or truncating anything.
fn write_direct<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let mut f = OpenOptions::new().write(true).open(path)?;
    // The node could have been swapped for something else since it was looked at.
    if !is_stream(&f.metadata()?.file_type()) {
        return Err(io::Error::other(
            "changed from a FIFO or device to another kind of file while being opened",
        ));
    }
    let mut w = io::BufWriter::new(&mut f);
    fill(&mut w)?;
    w.flush()
}

fn write_replace<F>(path: &Path, mode: Option<u32>, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let file = path.display().to_string();
    let name = path
        .file_name()
        .and_then(|s| s.to_str())
        .ok_or_else(|| Error::invalid(&file, "not a file name to write"))?;
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    // Exclusive creation cannot collide with a planted name, but a collision of two random
    // names is retried all the same.
    let (mut temp, f) = {
        let mut tries = 0;
        loop {
            let t = Temp::register(temp_path(dir, name));
            match create_exclusive(&t.path) {
                Ok(f) => break (t, f),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && tries < 8 => {
                    let mut t = t;
                    t.disarm(); // not ours: never remove it
                    tries += 1;
                }
                Err(e) => {
                    let mut t = t;
                    t.disarm();
                    return Err(Error::io(&file, e));
                }
            }
        }
    };
    let written = (|| -> io::Result<()> {
        #[cfg(unix)]
        if let Some(m) = mode {
            use std::os::unix::fs::PermissionsExt;
            f.set_permissions(std::fs::Permissions::from_mode(m))?;
        }
        #[cfg(not(unix))]
        let _ = mode;
        let mut w = io::BufWriter::new(&f);
        fill(&mut w)?;
        w.flush()?;
        drop(w);
        f.sync_all()?;
        std::fs::rename(&temp.path, path)
    })();
    match written {
        Ok(()) => {
            temp.disarm();
            // Make the rename itself durable; some systems cannot sync a directory.
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
            Ok(())
        }
        // `temp` is dropped here, which removes the temporary file.
        Err(e) => Err(Error::io(&file, e)),
    }
}

/// Opens a table for appending (creating it when missing) without following a symbolic link:
/// a link, a directory or any other non-regular file at `path` is refused. Returns the file and
/// whether it was empty.
pub fn open_append(path: &Path) -> Result<(File, bool)> {
    let file = path.display().to_string();
    if let Ok(m) = std::fs::symlink_metadata(path) {
        if m.file_type().is_symlink() {
            return Err(Error::invalid(
                &file,
                "is a symbolic link; cellseq does not append through links (remove it)",
            ));
        }
        if !m.is_file() {
            return Err(Error::invalid(&file, "is not a regular file"));
        }
    }
    let mut o = OpenOptions::new();
    o.create(true).append(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.mode(0o666)
            .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC);
    }
    let f = o.open(path).map_err(|e| Error::io(&file, e))?;
    let meta = f.metadata().map_err(|e| Error::io(&file, e))?;
    if !meta.is_file() {
        return Err(Error::invalid(&file, "is not a regular file"));
    }
    Ok((f, meta.len() == 0))
}

/// `(device, inode)` of an existing file, following links.
#[cfg(unix)]
fn identity(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
}

/// Refuses to write `output` when it is the file `input` (by any path, link or hard link),
/// unless `allow` (the command's `--overwrite-input` flag) is set.
pub fn ensure_not_input(input: &Path, output: &Path, allow: bool) -> Result<()> {
    if allow {
        return Ok(());
    }
    #[cfg(unix)]
    let same = identity(input).is_some() && identity(input) == identity(output);
    #[cfg(not(unix))]
    let same = match (std::fs::canonicalize(input), std::fs::canonicalize(output)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same {
        return Err(Error::invalid(
            output.display().to_string(),
            format!(
                "is the input file {}; write to another file, or pass --overwrite-input to \
                 replace the input",
                input.display()
            ),
        ));
    }
    Ok(())
}

/// True when `a` and `b` are the same existing file or directory (by device and inode on
/// Unix, by canonical path elsewhere).
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    return identity(a).is_some() && identity(a) == identity(b);
    #[cfg(not(unix))]
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Refuses an output directory whose own name is a symbolic link (its parents may be links):
/// results appended to a directory a link leads to could land anywhere the link was pointed,
/// so the directory must be named as it is. Every spelling counts: `LINK`, `LINK/`, `LINK/.`,
/// `LINK//`, `./LINK/.`, and a `..` that climbs out of a link (`LINK/..`, `LINK/sub/..`,
/// whose directory is reached through the link). The path is read component by component,
/// without following the last one (`symlink_metadata` follows a path that ends in `/`).
pub fn ensure_not_link_dir(dir: &Path) -> Result<()> {
    let refuse = |link: &Path| {
        let to = std::fs::read_link(link)
            .map(|t| t.display().to_string())
            .unwrap_or_else(|_| "?".into());
        Err(Error::invalid(
            dir.display().to_string(),
            format!(
                "{}is a symbolic link (to {to}); cellseq writes results only into a directory \
                 named as it is: give the directory itself with --out, or remove the link",
                if link == dir {
                    String::new()
                } else {
                    format!("names a directory through {}, which ", link.display())
                }
            ),
        ))
    };
    let is_link = |p: &Path| std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_symlink());
    // `components` drops `.` and trailing slashes; `..` pops the component it climbs out of,
    // and climbing out of a link is refused (the kernel would climb out of its target)
    let mut named = PathBuf::new();
    let mut depth = 0usize;
    for c in dir.components() {
        match c {
            Component::ParentDir if depth > 0 => {
                if is_link(&named) {
                    return refuse(&named);
                }
                named.pop();
                depth -= 1;
            }
            Component::ParentDir => named.push(".."),
            Component::Normal(_) => {
                named.push(c);
                depth += 1;
            }
            other => named.push(other),
        }
    }
    if depth > 0 && is_link(&named) {
        return refuse(&named);
    }
    Ok(())
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::{FileTypeExt, PermissionsExt, symlink};

    /// Every name in `dir` (hidden ones included).
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    // The crate's one `unsafe` block, in a test helper: std has no way to make a FIFO.
    #[allow(unsafe_code)]
    fn mkfifo(p: &Path) {
        let c = std::ffi::CString::new(p.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: `c` is a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
    }

    #[test]
    fn writes_new_file_and_leaves_no_temporary() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("out.ngc");
        write_file(&p, b"G0 X1\n").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"G0 X1\n");
        write_file(&p, b"G0 X2\n").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"G0 X2\n");
        assert_eq!(names(d.path()), vec!["out.ngc"]);
    }

    #[test]
    fn keeps_the_permission_bits_of_a_replaced_file() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("out.ngc");
        std::fs::write(&p, b"old").unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_file(&p, b"new").unwrap();
        let m = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        assert_eq!(m, 0o640);
    }

    #[test]
    fn symlink_at_the_target_is_replaced_not_followed() {
        let d = tempfile::tempdir().unwrap();
        let victim = d.path().join("victim.txt");
        std::fs::write(&victim, b"precious").unwrap();
        let out = d.path().join("out.ngc");
        symlink(&victim, &out).unwrap();
        write_file(&out, b"G-code").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        let m = std::fs::symlink_metadata(&out).unwrap();
        assert!(m.is_file(), "the link was replaced by a regular file");
        assert_eq!(std::fs::read(&out).unwrap(), b"G-code");
    }

    #[test]
    fn symlinks_planted_in_the_directory_are_never_written_through() {
        // Plant links at every name the old scheme used, and at many others: none is touched.
        let d = tempfile::tempdir().unwrap();
        let victim = d.path().join("victim.txt");
        std::fs::write(&victim, b"precious").unwrap();
        let pid = std::process::id();
        for n in [
            format!(".out.ngc.tmp{pid}"),
            ".out.ngc.tmp".to_string(),
            "out.ngc.tmp".to_string(),
        ] {
            symlink(&victim, d.path().join(n)).unwrap();
        }
        let out = d.path().join("out.ngc");
        for _ in 0..20 {
            write_file(&out, b"G-code").unwrap();
        }
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        assert_eq!(names(d.path()).len(), 5, "{:?}", names(d.path()));
    }

    #[test]
    fn exclusive_creation_refuses_an_existing_link() {
        let d = tempfile::tempdir().unwrap();
        let victim = d.path().join("victim.txt");
        std::fs::write(&victim, b"precious").unwrap();
        let link = d.path().join(".x.tmp");
        symlink(&victim, &link).unwrap();
        assert!(create_exclusive(&link).is_err());
        let dangling = d.path().join(".y.tmp");
        symlink(d.path().join("nothing"), &dangling).unwrap();
        assert!(create_exclusive(&dangling).is_err());
        assert!(!d.path().join("nothing").exists());
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
    }

    #[test]
    fn temporary_names_are_random() {
        let a = temp_path(Path::new("."), "out.ngc");
        let b = temp_path(Path::new("."), "out.ngc");
        assert_ne!(a, b);
        let s = a.file_name().unwrap().to_str().unwrap();
        assert!(s.starts_with(".out.ngc.") && s.ends_with(".tmp"), "{s}");
        assert_eq!(s.len(), ".out.ngc.".len() + 32 + 4);
        let long = "é".repeat(200);
        let t = temp_path(Path::new("."), &long);
        assert!(t.file_name().unwrap().len() < 255);
    }

    #[test]
    fn fifo_is_written_directly_and_stays_a_fifo() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("pipe");
        mkfifo(&p);
        let reader = {
            let p = p.clone();
            std::thread::spawn(move || std::fs::read(p).unwrap())
        };
        write_file(&p, b"through the pipe\n").unwrap();
        assert_eq!(reader.join().unwrap(), b"through the pipe\n");
        assert!(std::fs::symlink_metadata(&p).unwrap().file_type().is_fifo());
        assert_eq!(names(d.path()), vec!["pipe"]);
    }

    #[test]
    fn dev_null_stays_a_device() {
        write_file(Path::new("/dev/null"), b"nothing").unwrap();
        let m = std::fs::symlink_metadata("/dev/null").unwrap();
        assert!(m.file_type().is_char_device());
    }

    #[test]
    fn full_device_gives_an_error_naming_it() {
        if !Path::new("/dev/full").exists() {
            return;
        }
        let e = write_file(Path::new("/dev/full"), &[b'x'; 100_000]).unwrap_err();
        let s = e.to_string();
        assert!(s.starts_with("/dev/full: "), "{s}");
        assert!(
            std::fs::symlink_metadata("/dev/full")
                .unwrap()
                .file_type()
                .is_char_device()
        );
    }

    #[test]
    fn symlink_to_a_device_is_written_through() {
        let d = tempfile::tempdir().unwrap();
        let l = d.path().join("null-link");
        symlink("/dev/null", &l).unwrap();
        write_file(&l, b"x").unwrap();
        assert!(
            std::fs::symlink_metadata(&l)
                .unwrap()
                .file_type()
                .is_symlink()
        );
    }

    #[test]
    fn directory_target_is_refused() {
        let d = tempfile::tempdir().unwrap();
        let e = write_file(d.path(), b"x").unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        assert!(d.path().is_dir());
    }

    #[test]
    fn socket_target_is_refused() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("sock");
        let _l = std::os::unix::net::UnixListener::bind(&p).unwrap();
        let e = write_file(&p, b"x").unwrap_err().to_string();
        assert!(e.contains("socket"), "{e}");
        assert!(
            std::fs::symlink_metadata(&p)
                .unwrap()
                .file_type()
                .is_socket()
        );
        assert_eq!(names(d.path()), vec!["sock"]);
    }

    #[test]
    fn failed_fill_leaves_target_and_no_temporary() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("out.csv");
        std::fs::write(&p, b"old").unwrap();
        let e = write_with(&p, |w| {
            w.write_all(&[b'y'; 100_000])?;
            Err(io::Error::from_raw_os_error(libc::ENOSPC))
        })
        .unwrap_err()
        .to_string();
        assert!(e.starts_with(&p.display().to_string()), "{e}");
        assert!(e.contains("No space left"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert_eq!(names(d.path()), vec!["out.csv"]);
        assert!(!live().iter().any(|x| x.starts_with(d.path())));
    }

    #[test]
    fn missing_parent_is_an_error_without_leftovers() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("nowhere").join("out.json");
        let e = write_file(&p, b"{}").unwrap_err().to_string();
        assert!(e.contains("nowhere"), "{e}");
        assert!(names(d.path()).is_empty());
    }

    #[test]
    fn failed_rename_removes_the_temporary() {
        // A directory appears at the target between the check and the rename: the rename
        // fails (a file cannot replace a non-empty directory) and nothing is left behind.
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("out");
        let e = write_with(&p, |w| {
            std::fs::create_dir(&p)?;
            std::fs::write(p.join("inside"), b"x")?;
            w.write_all(b"data")
        });
        assert!(e.is_err());
        assert_eq!(names(d.path()), vec!["out"]);
        assert!(p.is_dir());
    }

    #[test]
    fn read_only_directory_is_an_error_without_leftovers() {
        let d = tempfile::tempdir().unwrap();
        let ro = d.path().join("ro");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        let r = write_file(&ro.join("out.json"), b"{}");
        // root ignores directory permissions: then the write simply succeeds
        if r.is_err() {
            assert!(names(&ro).is_empty());
        } else {
            assert_eq!(names(&ro), vec!["out.json"]);
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }

    #[test]
    fn append_refuses_links_and_special_files() {
        let d = tempfile::tempdir().unwrap();
        let victim = d.path().join("victim.txt");
        std::fs::write(&victim, b"precious").unwrap();
        let link = d.path().join("results.csv");
        symlink(&victim, &link).unwrap();
        let e = open_append(&link).unwrap_err().to_string();
        assert!(e.contains("symbolic link"), "{e}");
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        let fifo = d.path().join("traces.csv");
        mkfifo(&fifo);
        assert!(open_append(&fifo).is_err());
        assert!(open_append(d.path()).is_err());
        let (mut f, fresh) = open_append(&d.path().join("new.csv")).unwrap();
        assert!(fresh);
        f.write_all(b"a\n").unwrap();
        let (_, fresh) = open_append(&d.path().join("new.csv")).unwrap();
        assert!(!fresh);
    }

    #[test]
    fn output_that_is_the_input_is_refused_unless_allowed() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("a.ngc");
        std::fs::write(&a, b"G0 X0\n").unwrap();
        let e = ensure_not_input(&a, &a, false).unwrap_err().to_string();
        assert!(e.contains("--overwrite-input"), "{e}");
        // the same file through another spelling, a symbolic link and a hard link
        let other = d.path().join(".").join("a.ngc");
        assert!(ensure_not_input(&a, &other, false).is_err());
        let sl = d.path().join("s.ngc");
        symlink(&a, &sl).unwrap();
        assert!(ensure_not_input(&a, &sl, false).is_err());
        let hl = d.path().join("h.ngc");
        std::fs::hard_link(&a, &hl).unwrap();
        assert!(ensure_not_input(&a, &hl, false).is_err());
        assert!(ensure_not_input(&a, &a, true).is_ok());
        assert!(ensure_not_input(&a, &d.path().join("b.ngc"), false).is_ok());
        std::fs::write(d.path().join("c.ngc"), b"G0 X0\n").unwrap();
        assert!(ensure_not_input(&a, &d.path().join("c.ngc"), false).is_ok());
    }

    #[test]
    fn a_link_directory_is_refused_in_every_spelling() {
        let d = tempfile::tempdir().unwrap();
        let target = d.path().join("target");
        std::fs::create_dir_all(target.join("sub")).unwrap();
        let link = d.path().join("link");
        symlink(&target, &link).unwrap();
        let l = link.display().to_string();
        for form in [
            l.clone(),
            format!("{l}/"),
            format!("{l}/."),
            format!("{l}//"),
            format!("{l}/./"),
            format!("{l}/./."),
            format!("{l}/sub/.."),
            format!("{l}/.."),
            format!("{l}/../target"),
            format!("{}/./link/", d.path().display()),
        ] {
            let e = ensure_not_link_dir(Path::new(&form))
                .map(|_| "accepted".to_string())
                .unwrap_or_else(|e| e.to_string());
            assert!(e.contains("symbolic link"), "{form}: {e}");
        }
        // the directory itself, links among the parents, a new name, `..` out of a real one
        for ok in [
            target.clone(),
            link.join("sub"),
            link.join("sub/"),
            link.join("new"),
            target.join("sub/.."),
            d.path().join("nothing/here/."),
        ] {
            assert!(ensure_not_link_dir(&ok).is_ok(), "{}", ok.display());
        }
    }
}
