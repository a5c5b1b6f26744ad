//! The maps a reader navigates by are true: the README's strategy table names exactly the
//! strategy table's strategies, in order; the module maps of `strategy/mod.rs`,
//! `strategy/kmedoids/mod.rs` and `gpu/mod.rs` and the index `wgsl/README.md` name only
//! strategies that exist and files that exist, and every strategy, k-medoids method and WGSL
//! file appears in its map.

use meshletlab::strategy::{kmedoids::Mode, Kind, RETIRED};
use std::path::Path;

fn read(path: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(path)).unwrap()
}

/// The rows of the first markdown table after the line `heading` in `text` (each row's cells,
/// trimmed; the header and the separator left out). `prefix` is stripped from every line first
/// (`//! ` for a module doc).
fn first_table(text: &str, heading: &str, prefix: &str) -> Vec<Vec<String>> {
    let lines: Vec<&str> = text
        .lines()
        .map(|l| l.strip_prefix(prefix.trim_end()).unwrap_or(l).trim())
        .collect();
    let start = lines
        .iter()
        .position(|l| *l == heading)
        .unwrap_or_else(|| panic!("no `{heading}`"));
    let rows: Vec<Vec<String>> = lines[start..]
        .iter()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            l.trim_matches('|')
                .split(" | ")
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect();
    assert!(rows.len() > 2, "no table after `{heading}`");
    rows[2..].to_vec()
}

/// The names in backticks in `cell`.
fn ticked(cell: &str) -> Vec<String> {
    cell.split('`')
        .skip(1)
        .step_by(2)
        .map(|s| s.trim_matches(|c| c == '[' || c == ']').to_string())
        .collect()
}

fn names() -> Vec<&'static str> {
    Kind::ALL.iter().map(|k| k.name()).collect()
}

/// Strategy-like words (`kmedoids...`, `bsphere-...`) named in backticks in `text`.
fn strategy_words(text: &str) -> Vec<String> {
    ticked(text)
        .into_iter()
        .filter(|w| w.starts_with("kmedoids-") || w.starts_with("bsphere-") || w == "kmedoids")
        .filter(|w| !w.contains(['/', '.', ' ', ':']))
        .collect()
}

#[test]
fn the_readme_strategy_table_is_the_strategy_table() {
    let readme = read("README.md");
    let rows = first_table(&readme, "## Strategies", "");
    let listed: Vec<String> = rows.iter().map(|r| ticked(&r[0]).join("")).collect();
    assert_eq!(listed, names(), "README.md's strategy table");
    for r in &rows {
        for cell in &r[1..] {
            assert!(
                cell.len() <= 300,
                "a strategy cell over 300 characters: {cell}"
            );
        }
    }
    for (name, _) in RETIRED {
        assert!(!listed.iter().any(|n| n == name), "{name} is retired");
    }
}

#[test]
fn the_strategy_map_names_every_strategy_once_and_files_that_exist() {
    let doc = read("src/strategy/mod.rs");
    let rows = first_table(
        &doc,
        "| family | names | file | GPU kernel (driver, shader) |",
        "//!",
    );
    let mut listed: Vec<String> = rows.iter().flat_map(|r| ticked(&r[1])).collect();
    listed.retain(|n| !n.starts_with("S+"));
    let mut want: Vec<String> = names().iter().map(|s| s.to_string()).collect();
    listed.sort();
    want.sort();
    assert_eq!(listed, want, "strategy/mod.rs's map");
    for r in &rows {
        for f in ticked(&r[2]).iter().chain(&ticked(&r[3])) {
            if f.ends_with(".rs") {
                let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join(f);
                let in_strategy = Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("src/strategy")
                    .join(f);
                assert!(p.exists() || in_strategy.exists(), "{f} in strategy/mod.rs");
            }
        }
    }
}

#[test]
fn the_kmedoids_map_names_the_four_methods() {
    let doc = read("src/strategy/kmedoids/mod.rs");
    let rows = first_table(
        &doc,
        "| method ([`Mode`]) | name | driver | settings | on the GPU |",
        "//!",
    );
    let listed: Vec<String> = rows.iter().map(|r| ticked(&r[1]).join("")).collect();
    let modes: Vec<&str> = Mode::ALL.iter().map(|m| m.name()).collect();
    let family: Vec<&str> = names()
        .into_iter()
        .filter(|n| n.starts_with("kmedoids"))
        .collect();
    assert_eq!(listed, modes);
    assert_eq!(modes, family, "Mode::ALL against the strategy table");
    for r in &rows {
        for m in ticked(&r[4]) {
            if let Some(driver) = m.strip_prefix("gpu::") {
                let p = format!("src/gpu/{driver}.rs");
                assert!(
                    Path::new(env!("CARGO_MANIFEST_DIR")).join(&p).exists(),
                    "{p}"
                );
            }
        }
    }
}

#[test]
fn the_gpu_map_and_the_wgsl_index_cover_every_shader() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut shaders: Vec<String> = std::fs::read_dir(root.join("wgsl"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    shaders.sort();
    let doc = read("src/gpu/mod.rs");
    let rows = first_table(&doc, "| driver | shader (`wgsl/`) | CPU reference |", "//!");
    let mut mapped = Vec::new();
    for r in &rows {
        for d in ticked(&r[0]) {
            assert!(root.join(format!("src/gpu/{d}.rs")).exists(), "driver {d}");
        }
        mapped.extend(ticked(&r[1]).into_iter().filter(|s| s.ends_with(".wgsl")));
    }
    // Every kernel module is some driver's; the prelude goes in front of all of them.
    for s in &shaders {
        assert!(
            s == "prelude.wgsl" || mapped.contains(s),
            "{s} is in no row of gpu/mod.rs's map"
        );
    }
    for s in &mapped {
        assert!(
            shaders.contains(s),
            "gpu/mod.rs maps {s}, which is not in wgsl/"
        );
    }
    let index = read("wgsl/README.md");
    let entries: Vec<String> = index
        .lines()
        .filter_map(|l| l.strip_prefix("- `"))
        .filter_map(|l| l.split('`').next())
        .map(str::to_string)
        .collect();
    let mut sorted = entries.clone();
    sorted.sort();
    assert_eq!(sorted, shaders, "wgsl/README.md's entries");
    let known = names();
    // Module docs only: code holds names in strings (the retired ones among them).
    let module_doc = |t: &str| -> String {
        t.lines()
            .filter(|l| l.starts_with("//!"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    let strategy_doc = module_doc(&read("src/strategy/mod.rs"));
    let kmedoids_doc = module_doc(&read("src/strategy/kmedoids/mod.rs"));
    for text in [&module_doc(&doc), &index, &strategy_doc, &kmedoids_doc] {
        for w in strategy_words(text) {
            assert!(known.contains(&w.as_str()), "`{w}` is no strategy");
        }
    }
}

/// The figures of the front page's strategy table are cited, not typed: every number in a row's
/// last cell is a cell of the row of that strategy (on the bunny) in the results file the cell
/// names.
#[test]
fn the_front_page_figures_are_the_results_files_figures() {
    let rows = first_table(&read("src/lib.rs"), "# Which strategy", "//! ");
    let mut checked = 0;
    for row in &rows {
        let cite = row.last().unwrap();
        let Some(file) = ticked(cite).into_iter().find(|t| t.starts_with("results/")) else {
            continue;
        };
        // The strategy is the row's name in the results file: the cell's first ticked name, or
        // the row's strategy cell's.
        let opts = meshletlab::strategy::Options::default();
        let name = ticked(cite)
            .into_iter()
            .chain(ticked(&row[1]))
            .find(|t| meshletlab::strategy::by_name(t, &opts).is_ok())
            .unwrap_or_else(|| panic!("no strategy named in {row:?}"));
        let numbers: Vec<&str> = cite
            .split(|c: char| !(c.is_ascii_digit() || c == '.'))
            .map(|w| w.trim_matches('.'))
            .filter(|w| w.chars().any(|c| c.is_ascii_digit()) && *w != "64" && *w != "126")
            .collect();
        if numbers.is_empty() {
            continue;
        }
        let text = read(&file);
        let cells =
            |l: &str| -> Vec<String> { l.split('|').map(|c| c.trim().to_string()).collect() };
        // strategies.md: the first table (the bunny's), strategy in the first column;
        // kmedoids.md: the stanford_bunny rows, method in the third.
        let row_of = text.lines().map(cells).find(|c| {
            c.len() > 3
                && ((c[1] == name && file.ends_with("strategies.md"))
                    || (c[1] == "stanford_bunny" && c[3] == name))
        });
        let found = row_of.unwrap_or_else(|| panic!("no bunny row of {name} in {file}"));
        for n in numbers {
            assert!(
                found.iter().any(|c| c == n),
                "{name}: {n} is not in its row of {file}: {found:?}"
            );
        }
        checked += 1;
    }
    assert!(checked >= 6, "only {checked} rows cite figures");
}
