//! The library crates must never pull rerun, plotters or clap: users who depend on one paper
//! crate get the algorithm and the engine, not the drawing stack. And a paper crate depends
//! on no other paper crate: what two of them share lives in pf-core. Checked from
//! `cargo metadata`'s resolved graph.
//!
//! The graph is filtered to the host platform: offline, `cargo metadata` can only read the
//! manifests of crates already downloaded, and a build downloads only the host's (the
//! forbidden crates are not platform-specific, so the check loses nothing).

use serde_json::Value;
use std::collections::{BTreeSet, HashMap};
use std::process::Command;

const FORBIDDEN: [&str; 3] = ["rerun", "plotters", "clap"];

/// The host's target triple, from `rustc -vV`.
fn host() -> String {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let out = Command::new(rustc)
        .arg("-vV")
        .output()
        .expect("rustc -vV runs");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_owned))
        .expect("rustc -vV names the host")
}

fn metadata() -> Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--offline",
            "--filter-platform",
        ])
        .arg(host())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

/// Names of every package reachable from `root` through normal dependency edges.
fn normal_closure(meta: &Value, root: &str) -> BTreeSet<String> {
    closure(meta, root, false)
}

/// Names of every package reachable from `root`: through normal edges only, or through
/// every edge (normal, dev and build) when `all_kinds`.
fn closure(meta: &Value, root: &str, all_kinds: bool) -> BTreeSet<String> {
    let names: HashMap<&str, &str> = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["id"].as_str().unwrap(), p["name"].as_str().unwrap()))
        .collect();
    let nodes: HashMap<&str, &Value> = meta["resolve"]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| (n["id"].as_str().unwrap(), n))
        .collect();
    let start = names
        .iter()
        .find(|(_, n)| **n == root)
        .map(|(id, _)| *id)
        .unwrap_or_else(|| panic!("{root} is not in the workspace"));
    let mut seen = BTreeSet::new();
    let mut stack = vec![start];
    while let Some(id) = stack.pop() {
        if !seen.insert(id) {
            continue;
        }
        for dep in nodes[id]["deps"].as_array().unwrap() {
            let normal = dep["dep_kinds"]
                .as_array()
                .unwrap()
                .iter()
                .any(|k| k["kind"].is_null());
            if normal || all_kinds {
                stack.push(dep["pkg"].as_str().unwrap());
            }
        }
    }
    seen.into_iter().map(|id| names[id].to_string()).collect()
}

/// The workspace's package names.
fn members(meta: &Value) -> Vec<String> {
    meta["workspace_members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|id| {
            let id = id.as_str().unwrap();
            meta["packages"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["id"] == id)
                .unwrap()["name"]
                .as_str()
                .unwrap()
                .to_string()
        })
        .collect()
}

#[test]
fn library_crates_never_depend_on_the_drawing_stack() {
    let meta = metadata();
    let members = members(&meta);
    let libraries: Vec<&String> = members
        .iter()
        .filter(|m| m.as_str() != "pf-viz" && m.as_str() != "pf-tests")
        .collect();
    assert!(libraries.iter().any(|m| *m == "pf-core"));
    for lib in libraries {
        let closure = normal_closure(&meta, lib);
        for bad in FORBIDDEN {
            assert!(
                !closure.contains(bad),
                "{lib} pulls {bad} into its dependency tree"
            );
        }
    }
    // The check must be able to fail: pf-viz does pull them.
    let viz = normal_closure(&meta, "pf-viz");
    assert!(viz.contains("plotters") && viz.contains("clap"));
}

/// A paper crate reaches pf-core and no other workspace member, through any edge (normal,
/// dev or build): the papers stay independent, and pf-core depends on no member at all.
#[test]
fn paper_crates_never_depend_on_each_other() {
    let meta = metadata();
    let members = members(&meta);
    let papers: Vec<&String> = members
        .iter()
        .filter(|m| !["pf-core", "pf-viz", "pf-tests"].contains(&m.as_str()))
        .collect();
    // The five papers: a member added or renamed must be placed on one side or the other.
    assert_eq!(papers.len(), 5, "{papers:?}");
    for paper in &papers {
        let reach = closure(&meta, paper, true);
        for other in members.iter().filter(|m| m != paper) {
            assert!(
                other == "pf-core" || !reach.contains(other),
                "{paper} depends on {other}"
            );
        }
    }
    let core = closure(&meta, "pf-core", true);
    for m in members.iter().filter(|m| *m != "pf-core") {
        assert!(!core.contains(m), "pf-core depends on {m}");
    }
    // The check must be able to fail: pf-viz reaches every paper crate.
    let viz = normal_closure(&meta, "pf-viz");
    assert!(papers.iter().all(|p| viz.contains(*p)));
}
