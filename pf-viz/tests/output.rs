//! Where `pf-viz` output goes when the destination is not a plain file or a reading pipe:
//! a closed pipe or a full device on stdout, and `--out` on a link, a device or a directory.
//! Every failure is one line on stderr and a non-zero exit, never a panic or a replaced node.

mod common;

use std::fs::{self, OpenOptions};
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use common::{BIN, Scratch, one_line_error, pf_viz, pf_viz_ok};

/// Runs `pf-viz` with stdout on `stdout`, capturing stderr.
fn pf_viz_to(args: &[&str], stdout: Stdio) -> Output {
    Command::new(BIN)
        .args(args)
        .stdout(stdout)
        .stderr(Stdio::piped())
        .output()
        .expect("run pf-viz")
}

/// A pipe whose reading end is already closed, like `| head -1` once `head` has quit.
fn closed_pipe() -> Stdio {
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    writer.into()
}

/// `/dev/full`, where every write fails with ENOSPC.
fn dev_full() -> Stdio {
    assert_char_device("/dev/full");
    OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("open /dev/full")
        .into()
}

/// Fails loudly if a device node the tests rely on has been replaced.
fn assert_char_device(path: &str) {
    let t = fs::symlink_metadata(path).expect(path).file_type();
    assert!(t.is_char_device(), "{path} is no longer a character device");
}

/// Every subcommand's plain-text output, plus one `--json`, with its input files in `s`.
fn text_commands(s: &Scratch) -> Vec<Vec<String>> {
    let mut y = String::from("t,y\n");
    for k in 0..31 {
        y.push_str(&format!("{k},{}\n", ((k as f64) * 2.3).cos()));
    }
    let y = s.file("y.csv", &y);
    let cycle = s.path("cycle.csv");
    pf_viz_ok(&["dredge", "simulate", "--out", &cycle]);
    let ep = s.path("ep");
    pf_viz_ok(&["epf", "simulate", "--scenario", "van-plane", "--out", &ep]);
    let (det, init) = (format!("{ep}/detections.csv"), format!("{ep}/init.csv"));
    let theta = "--phi 0.8 --sigma 0.5 --rho 2 --particles 10";
    let lines = [
        "bench bootstrap --particles 10 --steps 1".to_owned(),
        "bench genealogy --particles 10 --steps 10".into(),
        "mpf calibrate --quick".into(),
        "mpf ratio".into(),
        "mpf ratio --json".into(),
        "mpf advise --p 1 --k 3000 --particles 10".into(),
        "mpf table2 --scale quick --mc 1".into(),
        "homotopy ellipses --step 17".into(),
        "homotopy rmse --realisations 1 --particles 50 --scale quick".into(),
        format!("smooth em --data {y} {theta} --replications 2 --lag 5"),
        format!("smooth sem --data {y} {theta} --iterations 2 --chains 2"),
        format!("smooth score --data {y} {theta} --replications 2"),
        format!("dredge simulate --out {}", s.path("again.csv")),
        format!("dredge estimate --data {cycle} --particles 20"),
        format!("epf simulate --scenario van-plane --out {}", s.path("ep2")),
        format!("epf track --data {det} --init {init} --particles 20"),
        format!("epf energies --data {det} --init {init} --frame 2"),
        format!(
            "report --out {} --only core --scale quick --no-rrd",
            s.path("rep")
        ),
    ];
    lines
        .iter()
        .map(|l| l.split_whitespace().map(str::to_owned).collect())
        .collect()
}

/// Each command writing to `stdout()` fails with exit status 1 and one line naming
/// `<stdout>` and `reason`, not a panic (status 101 and a backtrace).
fn each_fails_on_stdout(tag: &str, stdout: fn() -> Stdio, reason: &str) {
    let s = Scratch::new(tag);
    for args in text_commands(&s) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = pf_viz_to(&args, stdout());
        let what = format!("{args:?} > {tag}");
        let err = one_line_error(&out, &what, &["<stdout>", reason]);
        assert_eq!(out.status.code(), Some(1), "{what}: {err}");
        assert!(err.starts_with("error: "), "{what}: {err}");
    }
}

#[test]
fn text_output_to_a_closed_pipe_is_a_one_line_error() {
    each_fails_on_stdout("closed-pipe", closed_pipe, "Broken pipe");
}

#[test]
fn text_output_to_a_full_device_is_a_one_line_error() {
    each_fails_on_stdout("dev-full", dev_full, "No space left on device");
    assert_char_device("/dev/full");
}

/// `--out` through a symbolic link replaces the link's target and keeps the link, also a
/// relative link into another directory and a dangling one.
#[test]
fn out_through_a_symlink_writes_the_target_and_keeps_the_link() {
    let s = Scratch::new("symlink");
    let target = s.file("target.csv", "old\n");
    let link = s.path("link.csv");
    std::os::unix::fs::symlink("target.csv", &link).unwrap();
    pf_viz_ok(&["dredge", "simulate", "--out", &link]);
    assert!(
        fs::symlink_metadata(&link).unwrap().is_symlink(),
        "link kept"
    );
    let text = fs::read_to_string(&target).unwrap();
    assert!(text.starts_with("t,V_t,m_t"), "target written: {text:.40}");

    fs::create_dir(s.path("sub")).unwrap();
    let deep = s.path("sub/deep.csv");
    std::os::unix::fs::symlink("../fresh.csv", &deep).unwrap();
    pf_viz_ok(&["dredge", "simulate", "--out", &deep]);
    assert!(fs::symlink_metadata(&deep).unwrap().is_symlink());
    assert!(
        fs::read_to_string(s.path("fresh.csv"))
            .unwrap()
            .starts_with("t,")
    );

    let mut names: Vec<String> = fs::read_dir(s.dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["fresh.csv", "link.csv", "sub", "target.csv"]);
}

#[test]
fn out_on_a_directory_fails_on_one_line_and_creates_nothing() {
    let s = Scratch::new("dir");
    let dir = s.path("d");
    fs::create_dir(&dir).unwrap();
    let out = pf_viz(&["dredge", "simulate", "--out", &dir]);
    one_line_error(&out, "--out DIR", &[&dir, "directory"]);
    assert!(out.stdout.is_empty());
    assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);
    assert_eq!(fs::read_dir(s.dir()).unwrap().count(), 1, "only d");
}

/// The character device `/dev/<name>` (major 1, `minor`) to test writes against. As root,
/// `mknod` makes a node of the test's own in `dir`, so that a regression would replace that
/// node and not the system's; for other users the system's, which they cannot replace
/// either. `None` when a node was made but cannot be opened (a `nodev` mount).
fn test_device(dir: &Path, name: &str, minor: u32) -> Option<PathBuf> {
    let node = dir.join(name);
    let made = Command::new("mknod")
        .args(["-m", "666"])
        .arg(&node)
        .args(["c", "1", &minor.to_string()])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|st| st.success());
    if !made {
        return Some(PathBuf::from(format!("/dev/{name}")));
    }
    OpenOptions::new()
        .write(true)
        .open(&node)
        .is_ok()
        .then_some(node)
}

/// A null and a full device node of [`test_device`]'s, with the scratch that holds them.
/// Where a node of the test's own cannot be opened, the test fails rather than pass without
/// having written to a device: point `TMPDIR` at a file system that allows device nodes.
fn devices(name: &str) -> (Scratch, PathBuf, PathBuf) {
    let s = Scratch::new(name);
    match (
        test_device(s.dir(), "null", 3),
        test_device(s.dir(), "full", 7),
    ) {
        (Some(null), Some(full)) => (s, null, full),
        _ => panic!(
            "cannot open a device node made in {} (a nodev mount?): set TMPDIR to a file \
             system that allows device nodes",
            s.dir().display()
        ),
    }
}

/// The library's two writers on the same nodes: a null device takes the bytes, a full one
/// fails with the error naming it, and both stay devices (a rename would have replaced
/// them, as root).
#[test]
fn the_writers_write_devices_in_place() {
    use pf_viz::VizError;
    use pf_viz::io::{write_atomic, write_atomic_path};
    let (_s, null, full) = devices("dev-lib");
    let check = |p: &Path| assert_char_device(&p.to_string_lossy());
    check(&null);
    check(&full);
    write_atomic(&null, |w| w.write_all(b"gone").map_err(VizError::io(&null))).unwrap();
    write_atomic_path(&null, |tmp| {
        fs::write(tmp, b"gone").map_err(VizError::io(tmp))
    })
    .unwrap();
    let err = write_atomic(&full, |w| {
        w.write_all(&[0; 1 << 16]).map_err(VizError::io(&full))
    })
    .unwrap_err();
    assert!(err.to_string().contains("No space left"), "{err}");
    let err = write_atomic_path(&full, |tmp| fs::write(tmp, b"x").map_err(VizError::io(tmp)))
        .unwrap_err();
    assert!(
        matches!(&err, VizError::Io { path, .. } if *path == full),
        "{err}"
    );
    check(&null);
    check(&full);
}

/// A null device takes the bytes and stays a device (pf-viz run as root used to rename a
/// regular file over `/dev/null`); a full one refuses them, on one line, and no temporary
/// file is left beside either.
#[test]
fn out_on_a_device_is_written_in_place() {
    let (_s, null, full) = devices("dev");
    let (null, full) = (null.to_string_lossy(), full.to_string_lossy());
    assert_char_device(&null);
    pf_viz_ok(&["dredge", "simulate", "--out", &null]);
    assert_char_device(&null);

    assert_char_device(&full);
    let out = pf_viz(&["dredge", "simulate", "--out", &full]);
    one_line_error(&out, "--out full", &[&full, "No space left on device"]);
    assert!(out.stdout.is_empty(), "no success message");
    assert_char_device(&full);
    let parent = Path::new(&*null).parent().unwrap();
    assert!(
        !fs::read_dir(parent).unwrap().any(|e| e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .contains(".tmp-")),
        "no temporary file left beside the devices"
    );
}

/// A missing directory is reported on the path the user gave, not the temporary file.
#[test]
fn a_missing_directory_is_named_as_the_user_wrote_it() {
    let s = Scratch::new("nodir");
    let path = s.path("nodir/x.csv");
    let out = pf_viz(&["dredge", "simulate", "--out", &path]);
    let err = one_line_error(
        &out,
        "--out nodir/x.csv",
        &[&format!("{path}: No such file")],
    );
    assert!(!err.contains(".tmp-"), "{err}");
    assert!(!Path::new(&s.path("nodir")).exists());
}

/// A command that writes several files checks them all first: one that cannot be written
/// (here a directory in its place) fails the run before any of the others is replaced.
#[test]
fn a_set_of_files_fails_before_any_is_replaced() {
    let s = Scratch::new("set");
    let ep = s.path("ep");
    fs::create_dir_all(format!("{ep}/truth.csv")).unwrap();
    fs::write(format!("{ep}/detections.csv"), "old").unwrap();
    let out = pf_viz(&["epf", "simulate", "--scenario", "van-plane", "--out", &ep]);
    one_line_error(&out, "truth.csv a directory", &["truth.csv"]);
    assert_eq!(
        fs::read_to_string(format!("{ep}/detections.csv")).unwrap(),
        "old"
    );
    assert!(!Path::new(&format!("{ep}/init.csv")).exists());

    let r = s.path("r");
    fs::create_dir_all(format!("{r}/index.html")).unwrap();
    fs::write(format!("{r}/ess.png"), "old").unwrap();
    let out = pf_viz(&[
        "report", "--out", &r, "--scale", "quick", "--only", "core", "--no-rrd",
    ]);
    one_line_error(&out, "index.html a directory", &["index.html"]);
    assert_eq!(fs::read_to_string(format!("{r}/ess.png")).unwrap(), "old");
}

/// One failing section costs only itself. The failure is a real one, not a test hook: a
/// directory stands where the core section writes its first figure, so that section fails,
/// while the homotopy section after it runs as usual. The run still writes the homotopy
/// figures, `summary.json` (with the failure under `failed`), `index.html` and `REPORT.md`
/// (each naming the error), then exits non-zero with one `error:` line.
#[test]
fn a_failing_section_loses_nothing_else() {
    let s = Scratch::new("failing");
    let r = s.path("r");
    fs::create_dir_all(format!("{r}/genealogy.png")).unwrap();
    let out = pf_viz(&[
        "report",
        "--out",
        &r,
        "--scale",
        "quick",
        "--only",
        "core,homotopy",
        "--no-rrd",
    ]);
    assert_eq!(out.status.code(), Some(1), "exit status");
    let err = one_line_error(
        &out,
        "genealogy.png a directory",
        &["1 of 2 report section(s) failed", "core: ", "genealogy.png"],
    );
    assert!(err.starts_with("error: "), "{err}");
    assert!(out.stdout.is_empty(), "no success message");

    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(format!("{r}/summary.json")).unwrap()).unwrap();
    let sections = summary["sections"].as_object().unwrap();
    assert_eq!(sections.keys().collect::<Vec<_>>(), ["homotopy"]);
    let failed = summary["failed"].as_object().unwrap();
    assert_eq!(failed.keys().collect::<Vec<_>>(), ["core"]);
    let failure = failed["core"].as_str().unwrap();
    assert!(failure.contains("genealogy.png"), "{failure}");
    assert!(err.contains(failure), "{err} lacks {failure}");

    let pngs: Vec<String> = fs::read_dir(&r)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png") && n != "genealogy.png")
        .collect();
    assert!(!pngs.is_empty(), "no figure written");
    assert!(
        pngs.iter().all(|n| n.starts_with("homotopy-")),
        "only homotopy figures: {pngs:?}"
    );
    for page in ["index.html", "REPORT.md"] {
        let text = fs::read_to_string(format!("{r}/{page}")).unwrap();
        assert!(text.contains(failure), "{page} lacks the error");
        for f in &pngs {
            assert!(text.contains(f.as_str()), "{page} lacks {f}");
        }
    }
}
