//! Atomic file output: nothing pf-viz writes is ever seen half-written.
//!
//! Every file is first written to a temporary sibling (`.NAME.tmp-<pid>-<n>`, in the same
//! directory so the final `rename` is atomic), flushed and `fsync`ed, then renamed over the
//! target. On any error — or a panic in the writer — the temporary file is removed and the
//! target is left as it was. A symbolic link is followed, so its target is replaced and the
//! link kept; a device, FIFO or socket (`/dev/null`) is written in place, never replaced.
//! Errors name the user's path, never the temporary file.
//!
//! In an MPI run (feature `mpi`) only rank 0 writes: on every other rank each function here
//! does nothing and succeeds, so the ranks run the same program and one copy of each file
//! is written.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use serde::Serialize;

use crate::error::{Result, VizError};

/// Distinguishes temporary files of concurrent writers within one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Prefix-free marker that every temporary file name contains.
pub const TEMP_MARKER: &str = ".tmp-";

/// The temporary sibling of `path`: `.NAME.tmp-<pid>-<n>`, followed by `.EXT` when
/// `keep_extension` is set (for writers, like plotters', that pick a format by extension).
pub fn temp_path(path: &Path, keep_extension: bool) -> PathBuf {
    let dir = path.parent().unwrap_or(Path::new(""));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".to_owned());
    let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp = format!(".{name}{TEMP_MARKER}{}-{n}", std::process::id());
    if keep_extension && let Some(ext) = path.extension() {
        tmp.push('.');
        tmp.push_str(&ext.to_string_lossy());
    }
    dir.join(tmp)
}

/// Removes the temporary file on drop unless [`disarm`](TempGuard::disarm)ed, so an early
/// return or a panic never leaves it behind.
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl TempGuard {
    fn new(path: PathBuf) -> Self {
        TempGuard { path, armed: true }
    }

    fn disarm(&mut self) {
        self.armed = false;
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if self.armed {
            // Best effort: the writer may have failed before creating the file.
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Most symbolic links followed before giving up: a loop must fail, not hang.
const MAX_LINKS: usize = 40;

/// Where the bytes for a user's path go, once links are followed.
#[derive(Debug, PartialEq, Eq)]
enum Target {
    /// A regular file, existing or not: written through a temporary sibling and renamed.
    File(PathBuf),
    /// A device, FIFO or socket: written in place, since a rename would replace the node
    /// itself (turning `/dev/null` into a regular file).
    Special(PathBuf),
}

/// Follow `path` through symbolic links to the name that is to receive the bytes, so the
/// rename replaces the link's target and the link stays a link. A dangling link resolves
/// to the file it names, which is then created.
fn follow_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut p = path.to_owned();
    for _ in 0..MAX_LINKS {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = fs::read_link(&p)?;
                // A relative link is relative to the directory holding it.
                p = p.parent().unwrap_or(Path::new("")).join(to);
            }
            // Missing or not a link: this is the name to write (any other problem is
            // reported by the write itself).
            _ => return Ok(p),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

/// Classify `path` for writing.
///
/// # Errors
/// An I/O error naming `path` if it is a directory, a link loop, or cannot be examined.
fn target(path: &Path) -> Result<Target> {
    let real = follow_links(path).map_err(VizError::io(path))?;
    match fs::metadata(&real) {
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(Target::File(real)),
        Err(e) => Err(VizError::io(path)(e)),
        Ok(m) if m.is_file() => Ok(Target::File(real)),
        Ok(m) if m.is_dir() => Err(VizError::io(path)(ErrorKind::IsADirectory.into())),
        Ok(_) => Ok(Target::Special(real)),
    }
}

/// Open an existing device, FIFO or socket for writing, without creating or truncating.
fn open_special(dev: &Path, shown: &Path) -> Result<File> {
    OpenOptions::new()
        .write(true)
        .open(dev)
        .map_err(VizError::io(shown))
}

/// `fsync` a finished temporary file, then rename it over `target`. Errors name `shown`,
/// the path the user gave, never the temporary file.
fn commit(tmp: &Path, target: &Path, shown: &Path) -> Result<()> {
    File::open(tmp)
        .and_then(|f| f.sync_all())
        .map_err(VizError::io(shown))?;
    fs::rename(tmp, target).map_err(VizError::io(shown))?;
    // Persist the rename itself; not every platform lets a directory be opened and synced,
    // and the data are already safe, so a failure here is not an error.
    if let Some(dir) = target.parent().filter(|d| !d.as_os_str().is_empty())
        && let Ok(d) = File::open(dir)
    {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Whether this process writes files: always, except on MPI ranks other than 0.
fn writes() -> bool {
    pf_core::mc::dist::is_root()
}

/// Write `path` atomically: `write` fills a buffered writer on a temporary sibling, which is
/// renamed over `path` only if `write` and the flush succeed.
///
/// A symbolic link is followed (the target is replaced, the link kept). A device, FIFO or
/// socket is written in place, as a shell redirection would: there is nothing to rename,
/// and `/dev/null` must stay a device. A directory is an error.
///
/// # Errors
/// The writer's own error, or an I/O error naming `path` (never the temporary file). The
/// temporary file is removed in every failing case.
pub fn write_atomic<F>(path: &Path, write: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    if !writes() {
        return Ok(());
    }
    match target(path)? {
        Target::Special(dev) => write_buffered(open_special(&dev, path)?, path, write),
        Target::File(real) => {
            let tmp = temp_path(&real, false);
            let mut guard = TempGuard::new(tmp.clone());
            let file = OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&tmp)
                .map_err(VizError::io(path))?;
            // `commit` syncs the file before renaming it.
            write_buffered(file, path, write)?;
            commit(&tmp, &real, path)?;
            guard.disarm();
            Ok(())
        }
    }
}

/// Run `write` on a buffered `file` and flush it; errors name `shown`.
fn write_buffered<F>(file: File, shown: &Path, write: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    let mut w = BufWriter::new(file);
    write(&mut w)?;
    w.into_inner()
        .map_err(|e| VizError::io(shown)(e.into_error()))?;
    Ok(())
}

/// Write `path` atomically through a writer that wants a path of its own (plotters' bitmap
/// backend, Rerun's file sink). `write` gets a temporary file with `path`'s extension;
/// once it returns `Ok` the file is `fsync`ed and renamed over `path`.
///
/// Links, devices and directories are treated as by [`write_atomic`]; for a device the
/// temporary file lives in the system temp directory and is copied into the device.
///
/// # Errors
/// The writer's error, or an I/O error naming `path`. The temporary file is removed in
/// every failing case, also if `write` returned `Ok` without creating it.
pub fn write_atomic_path<F>(path: &Path, write: F) -> Result<()>
where
    F: FnOnce(&Path) -> Result<()>,
{
    if !writes() {
        return Ok(());
    }
    let target = target(path)?;
    let dir = match &target {
        Target::File(real) => real.parent().unwrap_or(Path::new("")).to_owned(),
        Target::Special(_) => std::env::temp_dir(),
    };
    // Named after `path`, not the link's target, so the writer sees the extension asked for.
    let name = path.file_name().unwrap_or("out".as_ref());
    let tmp = temp_path(&dir.join(name), true);
    let mut guard = TempGuard::new(tmp.clone());
    write(&tmp)?;
    if !tmp.exists() {
        let e = std::io::Error::new(ErrorKind::NotFound, "the writer created no file");
        return Err(VizError::io(path)(e));
    }
    match &target {
        Target::File(real) => {
            commit(&tmp, real, path)?;
            guard.disarm();
        }
        // The guard removes the scratch copy.
        Target::Special(dev) => copy_into(&tmp, dev, path)?,
    }
    Ok(())
}

/// Copy the finished temporary file `tmp` into the device `dev`; errors name `shown`.
fn copy_into(tmp: &Path, dev: &Path, shown: &Path) -> Result<()> {
    let mut src = File::open(tmp).map_err(VizError::io(shown))?;
    let mut dst = open_special(dev, shown)?;
    std::io::copy(&mut src, &mut dst)
        .and_then(|_| dst.flush())
        .map_err(VizError::io(shown))
}

/// Write `value` as pretty-printed JSON (with a final newline), atomically.
///
/// # Errors
/// A serialisation or I/O error naming `path`.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(|source| VizError::Json {
            path: path.to_owned(),
            source,
        })?;
        w.write_all(b"\n").map_err(VizError::io(path))
    })
}

/// Check, before anything is written, that each of `paths` can be written as a file (not a
/// directory, not a loop of links), so that a command writing several files fails before
/// the first of them rather than after some. Each file is still written atomically; a
/// failure while writing (a full disk) can leave the earlier ones new and the later ones
/// old.
///
/// # Errors
/// An I/O error naming the first path that cannot be written.
pub fn check_writable<'a>(paths: impl IntoIterator<Item = &'a Path>) -> Result<()> {
    if !writes() {
        return Ok(());
    }
    for p in paths {
        target(p)?;
    }
    Ok(())
}

/// Create the output directory (and its parents) and prove it is writable by creating and
/// removing a probe file, before any work is done.
///
/// # Errors
/// [`VizError::OutDir`] if the directory cannot be created or written to.
pub fn prepare_out_dir(dir: &Path) -> Result<()> {
    if !writes() {
        return Ok(());
    }
    let out_dir = |source| VizError::OutDir {
        path: dir.to_owned(),
        source,
    };
    fs::create_dir_all(dir).map_err(|e| {
        // `create_dir_all` says "File exists" for a file (or a device) in the way.
        if dir.exists() && !dir.is_dir() {
            out_dir(std::io::Error::new(
                std::io::ErrorKind::NotADirectory,
                "it exists and is not a directory",
            ))
        } else {
            out_dir(e)
        }
    })?;
    let probe = temp_path(&dir.join("pf-viz-probe"), false);
    let mut guard = TempGuard::new(probe.clone());
    OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .and_then(|mut f| f.write_all(b"probe"))
        .map_err(out_dir)?;
    fs::remove_file(&probe).map_err(out_dir)?;
    guard.disarm();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh, empty directory under the system temp dir, removed on drop.
    struct Scratch(PathBuf);

    impl Scratch {
        fn new(tag: &str) -> Self {
            let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
            let dir =
                std::env::temp_dir().join(format!("pf-viz-io-{tag}-{}-{n}", std::process::id()));
            let _ = fs::remove_dir_all(&dir);
            fs::create_dir_all(&dir).unwrap();
            Scratch(dir)
        }

        fn entries(&self) -> Vec<String> {
            let mut v: Vec<String> = fs::read_dir(&self.0)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    fn failure(path: &Path) -> VizError {
        VizError::PlotData {
            what: "test",
            message: format!("writer for {} failed on purpose", path.display()),
        }
    }

    #[test]
    fn success_leaves_only_the_target() {
        let s = Scratch::new("ok");
        let target = s.0.join("a.txt");
        write_atomic(&target, |w| {
            w.write_all(b"hello").map_err(VizError::io(&target))
        })
        .unwrap();
        assert_eq!(fs::read(&target).unwrap(), b"hello");
        assert_eq!(s.entries(), vec!["a.txt"]);
    }

    #[test]
    fn failing_writer_leaves_no_temp_file_and_keeps_the_old_target() {
        let s = Scratch::new("fail");
        let target = s.0.join("a.txt");
        fs::write(&target, b"old").unwrap();
        let err = write_atomic(&target, |w| {
            w.write_all(b"partial").unwrap();
            Err(failure(&target))
        })
        .unwrap_err();
        assert!(matches!(err, VizError::PlotData { .. }));
        assert_eq!(fs::read(&target).unwrap(), b"old");
        assert_eq!(s.entries(), vec!["a.txt"]);
    }

    #[test]
    fn panicking_writer_leaves_no_temp_file() {
        let s = Scratch::new("panic");
        let target = s.0.join("b.bin");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic(&target, |w| {
                w.write_all(b"partial").unwrap();
                panic!("writer panicked");
            });
        });
        assert!(r.is_err());
        assert!(s.entries().is_empty(), "{:?}", s.entries());
    }

    #[test]
    fn path_writer_gets_the_extension_and_is_cleaned_up_on_error() {
        let s = Scratch::new("path");
        let target = s.0.join("fig.png");
        let err = write_atomic_path(&target, |tmp| {
            assert_eq!(tmp.extension().unwrap(), "png");
            assert!(
                tmp.file_name()
                    .unwrap()
                    .to_string_lossy()
                    .starts_with(".fig.png.tmp-")
            );
            fs::write(tmp, b"half a png").unwrap();
            Err(failure(&target))
        })
        .unwrap_err();
        assert!(matches!(err, VizError::PlotData { .. }));
        assert!(s.entries().is_empty(), "{:?}", s.entries());

        write_atomic_path(&target, |tmp| {
            fs::write(tmp, b"png").map_err(VizError::io(tmp))
        })
        .unwrap();
        assert_eq!(s.entries(), vec!["fig.png"]);
    }

    #[test]
    fn path_writer_that_writes_nothing_is_an_error() {
        let s = Scratch::new("nothing");
        let target = s.0.join("x.rrd");
        let err = write_atomic_path(&target, |_| Ok(())).unwrap_err();
        assert!(matches!(err, VizError::Io { .. }), "{err}");
        assert!(s.entries().is_empty());
    }

    #[test]
    fn json_is_written_whole() {
        let s = Scratch::new("json");
        let target = s.0.join("s.json");
        write_json(&target, &serde_json::json!({"a": [1, 2, 3]})).unwrap();
        let v: serde_json::Value = serde_json::from_slice(&fs::read(&target).unwrap()).unwrap();
        assert_eq!(v["a"][2], 3);
    }

    #[test]
    fn out_dir_under_a_regular_file_is_rejected_and_nothing_is_created() {
        let s = Scratch::new("outdir");
        let file = s.0.join("plain");
        fs::write(&file, b"x").unwrap();
        let err = prepare_out_dir(&file.join("sub")).unwrap_err();
        assert!(matches!(err, VizError::OutDir { .. }), "{err}");
        assert_eq!(s.entries(), vec!["plain"]);
        // A good directory passes and keeps no probe.
        let good = s.0.join("good/nested");
        prepare_out_dir(&good).unwrap();
        assert_eq!(fs::read_dir(&good).unwrap().count(), 0);
    }

    #[test]
    fn a_symlink_is_followed_and_kept() {
        let s = Scratch::new("link");
        let target = s.0.join("target.csv");
        fs::write(&target, b"old").unwrap();
        let link = s.0.join("link.csv");
        std::os::unix::fs::symlink("target.csv", &link).unwrap();
        write_atomic(&link, |w| w.write_all(b"new").map_err(VizError::io(&link))).unwrap();
        assert!(fs::symlink_metadata(&link).unwrap().is_symlink());
        assert_eq!(fs::read(&target).unwrap(), b"new");
        // A path writer keeps the link's extension, for writers that pick a format by it.
        let png = s.0.join("fig.png");
        std::os::unix::fs::symlink("figure", &png).unwrap();
        write_atomic_path(&png, |tmp| {
            assert_eq!(tmp.extension().unwrap(), "png");
            fs::write(tmp, b"png").map_err(VizError::io(tmp))
        })
        .unwrap();
        assert!(fs::symlink_metadata(&png).unwrap().is_symlink());
        assert_eq!(fs::read(s.0.join("figure")).unwrap(), b"png");
        assert_eq!(s.entries(), ["fig.png", "figure", "link.csv", "target.csv"]);
    }

    #[test]
    fn a_link_loop_is_an_error_not_a_hang() {
        let s = Scratch::new("loop");
        let (a, b) = (s.0.join("a"), s.0.join("b"));
        std::os::unix::fs::symlink("b", &a).unwrap();
        std::os::unix::fs::symlink("a", &b).unwrap();
        let err = write_atomic(&a, |_| Ok(())).unwrap_err();
        assert!(err.to_string().contains("symbolic links"), "{err}");
        assert_eq!(s.entries(), ["a", "b"]);
    }

    #[test]
    fn a_directory_is_an_error_and_nothing_is_created() {
        let s = Scratch::new("isdir");
        let dir = s.0.join("d");
        fs::create_dir(&dir).unwrap();
        let err = write_atomic(&dir, |_| Ok(())).unwrap_err();
        assert!(
            matches!(&err, VizError::Io { path, .. } if *path == dir),
            "{err}"
        );
        let err = write_atomic_path(&dir, |tmp| fs::write(tmp, b"x").map_err(VizError::io(tmp)))
            .unwrap_err();
        assert!(matches!(err, VizError::Io { .. }), "{err}");
        assert_eq!(s.entries(), ["d"]);
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);
    }

    /// Errors name the path asked for: the temporary file is an implementation detail.
    #[test]
    fn errors_name_the_users_path_not_the_temporary_file() {
        let s = Scratch::new("nodir");
        let path = s.0.join("nodir/x.csv");
        let err = write_atomic(&path, |_| Ok(())).unwrap_err();
        assert!(
            matches!(&err, VizError::Io { path: p, .. } if *p == path),
            "{err}"
        );
        assert!(!err.to_string().contains(TEMP_MARKER), "{err}");
        let err = write_atomic_path(&path, |_| Ok(())).unwrap_err();
        assert!(
            matches!(&err, VizError::Io { path: p, .. } if *p == path),
            "{err}"
        );
        assert!(s.entries().is_empty());
    }

    /// A FIFO is written in place too: its reader gets the bytes, and it stays a FIFO.
    #[test]
    fn a_fifo_is_written_in_place() {
        use std::os::unix::fs::FileTypeExt;
        let s = Scratch::new("fifo");
        let fifo = s.0.join("p");
        // coreutils' mkfifo is on every Unix this runs on; its absence fails the test.
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(
            made.is_ok_and(|st| st.success()),
            "mkfifo {}",
            fifo.display()
        );
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || fs::read(fifo).unwrap())
        };
        write_atomic(&fifo, |w| {
            w.write_all(b"piped").map_err(VizError::io(&fifo))
        })
        .unwrap();
        assert_eq!(reader.join().unwrap(), b"piped");
        assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        assert_eq!(s.entries(), ["p"]);
    }
}
