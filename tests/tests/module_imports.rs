//! No two source files of a crate import each other, and pf-viz's drawing modules (`png/`,
//! `rrd/`) import neither `report/` nor each other: dependencies inside a crate point one way.
//!
//! A file imports another when it names a path into it (`use crate::a::b`, `super::x`,
//! `crate::a::f()`, or `use child::…`). A module and its direct child are not a pair: a
//! `mod.rs` that declares and re-exports its children while they name its shared items
//! (`super::Context`) is how Rust builds a module tree. Test modules are not scanned.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every crate of the workspace with a `src/` tree.
const CRATES: &[&str] = &[
    "pf-core",
    "pf-smooth",
    "pf-mpf",
    "pf-homotopy",
    "pf-dredge",
    "pf-epf",
    "pf-viz",
];

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

/// The `src/` directory of a workspace crate.
fn src_of(krate: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(krate)
        .join("src")
}

#[test]
fn no_two_files_import_each_other() {
    let mut wrong = Vec::new();
    for krate in CRATES {
        let graph = imports(&src_of(krate));
        for (f, to) in &graph {
            for g in to {
                let (mf, mg) = (module_of(f), module_of(g));
                let parent_child = mf.len() + 1 == mg.len() && mg.starts_with(&mf)
                    || mg.len() + 1 == mf.len() && mf.starts_with(&mg);
                if f < g && !parent_child && graph.get(g).is_some_and(|back| back.contains(f)) {
                    wrong.push(format!("{krate}: {f} and {g} import each other"));
                }
            }
        }
    }
    assert!(wrong.is_empty(), "{wrong:#?}");
}

#[test]
fn pf_viz_draws_without_the_report() {
    let graph = imports(&src_of("pf-viz"));
    // The scan sees both kinds of import, so an empty result below means something.
    assert!(graph["png/table.rs"].contains("figure.rs"), "{graph:?}");
    assert!(
        graph["report/page.rs"].contains("report/mod.rs"),
        "{graph:?}"
    );
    let part = |p: &str| p.split('/').next().unwrap_or_default().to_owned();
    let draws = |p: &str| p == "png" || p == "rrd";
    let mut wrong = Vec::new();
    for (f, to) in &graph {
        for g in to {
            let (pf, pg) = (part(f), part(g));
            if draws(&pf) && (pg == "report" || (draws(&pg) && pf != pg)) {
                wrong.push(format!("{f} imports {g}"));
            }
        }
    }
    assert!(wrong.is_empty(), "{wrong:#?}");
}

#[test]
fn a_planted_cycle_is_found() {
    let dir = std::env::temp_dir().join(format!("pf-imports-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(&src).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\n").unwrap();
    std::fs::write(src.join("a.rs"), "use crate::b::f;\npub fn g() {}\n").unwrap();
    std::fs::write(src.join("b.rs"), "use super::a::{g};\npub fn f() {}\n").unwrap();
    let graph = imports(&src);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(graph["a.rs"].contains("b.rs"), "{graph:?}");
    assert!(graph["b.rs"].contains("a.rs"), "{graph:?}");
}
