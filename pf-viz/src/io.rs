//! Atomic file output: nothing pf-viz writes is ever seen half-written.
//!
//! Every file is first written to a temporary sibling (`.NAME.tmp-<pid>-<n>`, in the same
//! directory so the final `rename` is atomic), flushed and `fsync`ed, then renamed over the
//! target. On any error — or a panic in the writer — the temporary file is removed and the
//! target is left as it was.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, Write};
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

/// `fsync` a finished temporary file, then rename it over `target`.
fn commit(tmp: &Path, target: &Path) -> Result<()> {
    File::open(tmp)
        .and_then(|f| f.sync_all())
        .map_err(VizError::io(tmp))?;
    fs::rename(tmp, target).map_err(VizError::io(target))?;
    // Persist the rename itself; not every platform lets a directory be opened and synced,
    // and the data are already safe, so a failure here is not an error.
    if let Some(dir) = target.parent().filter(|d| !d.as_os_str().is_empty())
        && let Ok(d) = File::open(dir)
    {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Write `path` atomically: `write` fills a buffered writer on a temporary sibling, which is
/// renamed over `path` only if `write` and the flush succeed.
///
/// # Errors
/// The writer's own error, or an I/O error naming the path at fault. The temporary file is
/// removed in every failing case.
pub fn write_atomic<F>(path: &Path, write: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    let tmp = temp_path(path, false);
    let mut guard = TempGuard::new(tmp.clone());
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(VizError::io(&tmp))?;
    let mut w = BufWriter::new(file);
    write(&mut w)?;
    let file = w
        .into_inner()
        .map_err(|e| VizError::io(&tmp)(e.into_error()))?;
    file.sync_all().map_err(VizError::io(&tmp))?;
    drop(file);
    commit(&tmp, path)?;
    guard.disarm();
    Ok(())
}

/// Write `path` atomically through a writer that wants a path of its own (plotters' bitmap
/// backend, Rerun's file sink). `write` gets a temporary sibling with the same extension;
/// once it returns `Ok` the file is `fsync`ed and renamed over `path`.
///
/// # Errors
/// The writer's error, or an I/O error naming the path at fault. The temporary file is
/// removed in every failing case, also if `write` returned `Ok` without creating it.
pub fn write_atomic_path<F>(path: &Path, write: F) -> Result<()>
where
    F: FnOnce(&Path) -> Result<()>,
{
    let tmp = temp_path(path, true);
    let mut guard = TempGuard::new(tmp.clone());
    write(&tmp)?;
    commit(&tmp, path)?;
    guard.disarm();
    Ok(())
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

/// Create the output directory (and its parents) and prove it is writable by creating and
/// removing a probe file, before any work is done.
///
/// # Errors
/// [`VizError::OutDir`] if the directory cannot be created or written to.
pub fn prepare_out_dir(dir: &Path) -> Result<()> {
    let out_dir = |source| VizError::OutDir {
        path: dir.to_owned(),
        source,
    };
    fs::create_dir_all(dir).map_err(out_dir)?;
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
}
