//! # pf-viz: figures and recordings for the pf papers
//!
//! The `pf-viz` binary runs the experiments of the paper crates and turns their result
//! structs into PNG figures (plotters, headless, embedded font), Rerun recordings (`.rrd`,
//! behind the default feature `rrd`) and one `summary.json`. It draws; it does no
//! statistics.
//!
//! | module | holds |
//! |---|---|
//! | [`cli`] | the clap command line |
//! | [`bench`](mod@bench) | `pf-viz bench bootstrap` |
//! | [`cmd`] | the paper subcommands, one module per paper |
//! | [`data`] | reading observation CSV files |
//! | [`report`] | `pf-viz report`: the registry of sections, one file per paper |
//! | [`figure`] | plain data types that `png` and `rrd` draw and `report` fills |
//! | [`png`] | plot kinds, each a function from plain data to a PNG |
//! | `rrd` | Rerun loggers (feature `rrd`) |
//! | [`io`] | atomic file writes |
//! | [`error`] | [`VizError`], printed by the binary as one line |
//!
//! Dependencies point one way: [`cli`] converts its arguments into [`report::Options`];
//! [`report`] runs the paper crates, fills [`figure`] types and hands them to [`png`] and
//! `rrd`, which depend on neither `report` nor each other. No two files import each other
//! (a unit test here checks it).

pub mod bench;
pub mod cli;
pub mod cmd;
pub mod data;
pub mod error;
pub mod figure;
pub mod io;
pub mod png;
pub mod report;
#[cfg(feature = "rrd")]
pub mod rrd;

pub use error::{Result, VizError};

use cli::{BenchCommand, Cli, Command};
use cmd::print_line;

/// Execute a parsed command line.
///
/// # Errors
/// Whatever the subcommand fails with; nothing half-written is left behind.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Report(args) => {
            let options = report::Options::from(args);
            let summary = report::run(&options)?;
            print_line(format_args!(
                "pf-viz: wrote {} section(s) to {}",
                summary.sections.len(),
                options.out.display()
            ))?;
            Ok(())
        }
        Command::Bench(BenchCommand::Bootstrap(args)) => {
            let r = bench::bootstrap(&args)?;
            if args.json {
                cmd::print_json(&r)?;
            } else {
                let runs = if r.repeat > 1 {
                    format!(
                        " (fastest of {}; median {:.3} s)",
                        r.repeat, r.seconds_median
                    )
                } else {
                    String::new()
                };
                print_line(format_args!(
                    "bootstrap AR(1): N = {}, n = {}, {} thread(s): {:.3} s{runs}, {:.2} ns per particle-step, log-likelihood {:.3}",
                    r.particles, r.steps, r.threads, r.seconds, r.ns_per_particle_step, r.loglik
                ))?;
            }
            Ok(())
        }
        Command::Bench(BenchCommand::Genealogy(args)) => {
            let r = bench::genealogy(&args)?;
            if args.json {
                cmd::print_json(&r)?;
            } else {
                print_line(format_args!(
                    "pruned path storage, N = {}, n = {}: peak {} nodes ({:.1} MB) against {:.1} MB for full storage; peak RSS {}; {:.1} s",
                    r.particles,
                    r.steps,
                    r.peak_nodes,
                    r.tree_peak_bytes as f64 / 1e6,
                    r.full_storage_bytes as f64 / 1e6,
                    r.peak_rss_bytes
                        .map_or("unknown".into(), |b| format!("{:.1} MB", b as f64 / 1e6)),
                    r.seconds
                ))?;
            }
            Ok(())
        }
        Command::Smooth(c) => cmd::smooth::run(c),
        Command::Mpf(c) => cmd::mpf::run(c),
        Command::Homotopy(c) => cmd::homotopy::run(c),
        Command::Dredge(c) => cmd::dredge::run(c),
        Command::Epf(c) => cmd::epf::run(c),
    }
}

#[cfg(test)]
mod tests {
    use std::collections::{BTreeMap, BTreeSet};
    use std::path::{Path, PathBuf};

    /// Imports that another part of the work removes; each entry must still exist, so that
    /// it is dropped from here as soon as the import goes.
    const KNOWN: &[(&str, &str)] = &[("rrd/epf.rs", "report/epf.rs")];

    /// The source file of module `m` (`[]` is the crate root), if there is one.
    fn file_of(src: &Path, m: &[String]) -> Option<String> {
        if m.is_empty() {
            return Some("lib.rs".into());
        }
        let base = m.join("/");
        [format!("{base}.rs"), format!("{base}/mod.rs")]
            .into_iter()
            .find(|f| src.join(f).is_file())
    }

    /// The module path of source file `f` (relative to `src/`).
    fn module_of(f: &str) -> Vec<String> {
        let f = f.strip_suffix(".rs").unwrap();
        let f = f.strip_suffix("/mod").unwrap_or(f);
        if f == "lib" {
            Vec::new()
        } else {
            f.split('/').map(str::to_owned).collect()
        }
    }

    /// The deepest module named by `path` (e.g. `png::genealogy::render`) from module `at`.
    fn resolve(src: &Path, at: &[String], path: &[&str]) -> Vec<String> {
        let mut m = at.to_vec();
        for seg in path {
            let mut next = m.clone();
            next.push((*seg).to_owned());
            if file_of(src, &next).is_none() {
                break;
            }
            m = next;
        }
        m
    }

    /// Expand the use tree or path at the start of `s` into its paths (`a::{b, c::d}` gives
    /// `a::b` and `a::c::d`); returns how much of `s` it read.
    fn paths<'a>(s: &'a str, prefix: &[&'a str], out: &mut Vec<Vec<&'a str>>) -> usize {
        let skip_ws = |i: usize| i + s[i..].len() - s[i..].trim_start().len();
        let mut segs = prefix.to_vec();
        let mut i = 0;
        loop {
            let len = s[i..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(s.len() - i);
            if len == 0 && s[i..].starts_with('{') {
                i += 1;
                loop {
                    i = skip_ws(i);
                    if s[i..].starts_with('}') {
                        return i + 1;
                    }
                    i += paths(&s[i..], &segs, out);
                    i = skip_ws(i);
                    if s[i..].starts_with(',') {
                        i += 1;
                    } else {
                        return i + usize::from(s[i..].starts_with('}'));
                    }
                }
            }
            segs.push(&s[i..i + len]);
            i += len;
            if len > 0 && s[i..].starts_with("::") {
                i += 2;
            } else {
                out.push(segs);
                return i;
            }
        }
    }

    /// Every path of the use tree or path at the start of `s`.
    fn paths_at(s: &str) -> Vec<Vec<&str>> {
        let mut out = Vec::new();
        paths(s, &[], &mut out);
        out
    }

    /// Every file of `src/` with the files it imports: paths through `crate::` or `super::`
    /// anywhere in its code, and `use` of its own child modules. A parent naming a child
    /// (`mod x;`, `x::f()`) declares it and is not counted; comments and test modules are
    /// left out.
    fn imports(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
        fn walk(dir: &Path, src: &Path, out: &mut Vec<String>) {
            for e in std::fs::read_dir(dir).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    walk(&p, src, out);
                } else if p.extension().is_some_and(|e| e == "rs") {
                    let rel = p.strip_prefix(src).unwrap();
                    out.push(rel.to_string_lossy().replace('\\', "/"));
                }
            }
        }
        let mut files = Vec::new();
        walk(src, src, &mut files);
        let mut graph = BTreeMap::new();
        for f in files {
            let text = std::fs::read_to_string(src.join(&f)).unwrap();
            let code: String = text
                .split("#[cfg(test)]\nmod tests")
                .next()
                .unwrap()
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            let here = module_of(&f);
            let mut to = BTreeSet::new();
            let mut targets = Vec::new();
            for (i, _) in code.match_indices("crate::") {
                for p in paths_at(&code[i + 7..]) {
                    targets.push(resolve(src, &[], &p));
                }
            }
            for (i, _) in code.match_indices("super::") {
                if code[..i].ends_with("super::") {
                    continue;
                }
                let mut up = here.clone();
                let mut j = i;
                while code[j..].starts_with("super::") {
                    up.pop();
                    j += 7;
                }
                for p in paths_at(&code[j..]) {
                    targets.push(resolve(src, &up, &p));
                }
            }
            for (i, _) in code.match_indices("use ") {
                if code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                    continue;
                }
                let first = code[i + 4..].split("::").next().unwrap_or_default();
                let mut child = here.clone();
                child.push(first.to_owned());
                if file_of(src, &child).is_some() {
                    for p in paths_at(&code[i + 4..]) {
                        targets.push(resolve(src, &here, &p));
                    }
                }
            }
            for t in targets {
                let g = file_of(src, &t).unwrap();
                if g != f {
                    to.insert(g);
                }
            }
            graph.insert(f, to);
        }
        graph
    }

    /// `png/` and `rrd/` import nothing from `report/` or from each other, and no two files
    /// of pf-viz import each other.
    #[test]
    fn imports_point_one_way() {
        let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
        let graph = imports(&src);
        // The scan sees both kinds of import.
        assert!(graph["png/table.rs"].contains("figure.rs"), "{graph:?}");
        assert!(
            graph["report/page.rs"].contains("report/mod.rs"),
            "{graph:?}"
        );
        let known = |a: &str, b: &str| {
            KNOWN
                .iter()
                .any(|&(x, y)| (x, y) == (a, b) || (y, x) == (a, b))
        };
        let mut wrong = Vec::new();
        for (f, to) in &graph {
            for g in to {
                let part = |p: &str| p.split('/').next().unwrap().to_owned();
                let (pf, pg) = (part(f), part(g));
                let draws = |p: &str| p == "png" || p == "rrd";
                if known(f, g) {
                    continue;
                }
                if draws(&pf) && (pg == "report" || (draws(&pg) && pf != pg)) {
                    wrong.push(format!("{f} imports {g}"));
                }
                if f < g && graph.get(g).is_some_and(|back| back.contains(f)) {
                    wrong.push(format!("{f} and {g} import each other"));
                }
            }
        }
        assert!(wrong.is_empty(), "{wrong:#?}");
        for (a, b) in KNOWN {
            assert!(
                graph.get(*a).is_some_and(|to| to.contains(*b)),
                "{a} no longer imports {b}: remove it from KNOWN"
            );
        }
    }
}
