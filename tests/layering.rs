//! The architecture the front page promises, checked on the source: data flows one way through the
//! crate's rooms (no module imports a later room), and no two files import each other, directly or
//! through others. Test modules (`#[cfg(test)] mod tests`) are left out: a test may build its
//! input with a higher room.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The rooms in data-flow order; a file may import its own room and earlier ones.
const ROOMS: &[&[&str]] = &[
    &["common", "atomic"],
    &["mesh"],
    &["adjacency"],
    &["meshlet"],
    &["strategy"],
    &["lod", "compress"],
    &["gpu", "render"],
    &["fuzz"],
    &["bench"],
    &["cli"],
];

fn rank(room: &str) -> Option<usize> {
    ROOMS.iter().position(|r| r.contains(&room))
}

/// Every `.rs` file under `dir`, as (module path, file).
fn files(dir: &Path, module: &[String], out: &mut Vec<(Vec<String>, PathBuf)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        let name = p.file_stem().unwrap().to_str().unwrap().to_string();
        if p.is_dir() {
            let mut m = module.to_vec();
            m.push(name);
            files(&p, &m, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let mut m = module.to_vec();
            if !["mod", "lib", "main"].contains(&name.as_str()) {
                m.push(name);
            }
            out.push((m, p));
        }
    }
}

/// The source without comments, string contents and the unit-test module.
fn code(path: &Path) -> String {
    let s = std::fs::read_to_string(path).unwrap();
    let s = s.split("#[cfg(test)]\nmod tests").next().unwrap();
    let mut out = String::new();
    for line in s.lines() {
        let line = line.split("//").next().unwrap();
        // Drop string literals (paths in messages are not imports).
        let mut inside = false;
        for c in line.chars() {
            if c == '"' {
                inside = !inside;
            } else if !inside {
                out.push(c);
            }
        }
        out.push('\n');
    }
    out
}

/// The module paths a file names: `crate::a::b`, `super::a` and `self::a`, with `use` groups
/// (`a::{b, c::d}`) expanded one level.
fn references(module: &[String], code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    for head in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(i) = code[from..].find(head) {
            let at = from + i;
            from = at + head.len();
            if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_') {
                continue;
            }
            // `super` is the parent module both in `x/mod.rs` (module `x`) and in `x/y.rs`
            // (module `x::y`).
            let base: Vec<String> = match head {
                "crate::" => vec![],
                "self::" => module.to_vec(),
                _ => module[..module.len().saturating_sub(1)].to_vec(),
            };
            let rest = &code[from..];
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(rest.len());
            let path: Vec<String> = rest[..end]
                .split("::")
                .filter(|p| !p.is_empty())
                .map(String::from)
                .collect();
            let mut full = base.clone();
            full.extend(path.iter().cloned());
            if rest[end..].starts_with('{') {
                let group = &rest[end + 1..rest[end..].find('}').map_or(end, |j| end + j)];
                for item in group.split(',').map(str::trim).filter(|g| !g.is_empty()) {
                    let mut p = full.clone();
                    p.extend(item.split("::").map(|s| s.trim().to_string()));
                    out.push(p);
                }
            } else {
                out.push(full);
            }
        }
    }
    out
}

#[test]
fn no_room_imports_a_later_one_and_no_files_import_each_other() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &[], &mut all);
    let modules: BTreeMap<Vec<String>, PathBuf> = all.iter().cloned().collect();
    let resolve = |path: &[String]| {
        (1..=path.len())
            .rev()
            .map(|n| path[..n].to_vec())
            .find(|p| modules.contains_key(p))
    };
    let mut upward = Vec::new();
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (module, file) in &all {
        let Some(room) = module.first() else { continue };
        for r in references(module, &code(file)) {
            let Some(target) = resolve(&r) else { continue };
            if let (Some(a), Some(b)) = (rank(room), target.first().and_then(|t| rank(t))) {
                if b > a {
                    upward.push(format!("{} imports {}", file.display(), target.join("::")));
                }
            }
            // Edges into a folder's mod.rs are a parent's shared items, not a sibling cycle.
            let into_dir = modules[&target].file_stem().is_some_and(|s| s == "mod");
            if target != *module && !into_dir && !target.is_empty() {
                edges.entry(module.clone()).or_default().insert(target);
            }
        }
    }
    assert!(upward.is_empty(), "upward imports:\n{}", upward.join("\n"));
    // A cycle: a file that reaches itself along the import edges.
    let mut cycles = Vec::new();
    for start in edges.keys() {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<Vec<String>> = edges[start].iter().cloned().collect();
        while let Some(m) = stack.pop() {
            if m == *start {
                cycles.push(start.join("::"));
                break;
            }
            if seen.insert(m.clone()) {
                stack.extend(edges.get(&m).into_iter().flatten().cloned());
            }
        }
    }
    assert!(cycles.is_empty(), "files on an import cycle: {cycles:?}");
}

#[test]
fn the_checker_sees_an_upward_import_and_a_cycle() {
    // The parser on a hand-made file: `crate::` paths, `super::` groups.
    let refs = references(
        &["strategy".into(), "kmedoids".into(), "flat".into()],
        "use super::{assign::members, split};\nuse crate::gpu::Gpu;",
    );
    let names: Vec<String> = refs.iter().map(|r| r.join("::")).collect();
    assert_eq!(
        names,
        [
            "gpu::Gpu",
            "strategy::kmedoids::assign::members",
            "strategy::kmedoids::split"
        ]
    );
    assert!(rank("gpu") > rank("strategy"));
}
