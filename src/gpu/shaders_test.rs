//! Every WGSL module (behind the prelude) parses, validates with naga and emits SPIR-V, and its
//! interface is the one the Rust driver declares: the `Params` struct member by member against
//! the family's [`ParamBlock`], every binding by name and access against its [`BindingSet`], and
//! read-only wherever no kernel of the module writes.

use super::{Access, BindingSet, ParamBlock};
use naga::valid::GlobalUse;

fn source(file: &str) -> String {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    let parts = super::WGSL_PARTS
        .iter()
        .filter(|(_, users)| users.contains(&file))
        .map(|(part, _)| read(part));
    let generated = super::WGSL_GENERATED
        .iter()
        .filter(|(_, user)| *user == file)
        .map(|(g, _)| {
            std::fs::read_to_string(std::path::Path::new(env!("OUT_DIR")).join(g)).unwrap()
        });
    generated.collect::<String>() + &read("prelude.wgsl") + &read(file) + &parts.collect::<String>()
}

fn parse(file: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    let src = source(file);
    let module = naga::front::wgsl::parse_str(&src)
        .unwrap_or_else(|e| panic!("{file}: {}", e.emit_to_string(&src)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{file}: {e:?}"));
    (module, info)
}

/// Checks `file`'s `Params` against `P` and its bindings against `B`; returns the problems.
fn interface<'b, P: ParamBlock, B: BindingSet<'b>>(file: &str) -> Vec<String> {
    let (module, info) = parse(file);
    let mut bad = Vec::new();
    // Params: binding 0, a struct of u32 members named and placed as the Rust fields.
    let params = module
        .global_variables
        .iter()
        .find(|(_, g)| g.binding.as_ref().is_some_and(|b| b.binding == 0))
        .map(|(_, g)| &module.types[g.ty]);
    match params.map(|t| &t.inner) {
        Some(naga::TypeInner::Struct { members, span }) => {
            let names: Vec<_> = members
                .iter()
                .map(|m| m.name.as_deref().unwrap_or(""))
                .collect();
            if names != P::FIELDS {
                bad.push(format!(
                    "{file}: Params members {names:?}, Rust {:?}",
                    P::FIELDS
                ));
            }
            for (i, m) in members.iter().enumerate() {
                let scalar = matches!(module.types[m.ty].inner, naga::TypeInner::Scalar(s) if s == naga::Scalar::U32);
                if m.offset != 4 * i as u32 || !scalar {
                    bad.push(format!(
                        "{file}: Params member {i} is not a u32 at byte {}",
                        4 * i
                    ));
                }
            }
            if *span as usize != std::mem::size_of::<P>() {
                bad.push(format!(
                    "{file}: Params is {span} bytes, Rust {}",
                    std::mem::size_of::<P>()
                ));
            }
        }
        _ => bad.push(format!("{file}: no Params struct at binding 0")),
    }
    // Storage bindings 1..: names, declared access, and whether any kernel writes.
    let mut storage: Vec<_> = module
        .global_variables
        .iter()
        .filter_map(|(h, g)| {
            let b = g.binding.as_ref()?;
            let naga::AddressSpace::Storage { access } = g.space else {
                return None;
            };
            let written = (0..module.entry_points.len())
                .any(|e| info.get_entry_point(e)[h].contains(GlobalUse::WRITE));
            let declared = if access.contains(naga::StorageAccess::STORE) {
                Access::ReadWrite
            } else {
                Access::Read
            };
            Some((
                b.binding,
                g.name.clone().unwrap_or_default(),
                declared,
                written,
            ))
        })
        .collect();
    storage.sort_by_key(|s| s.0);
    let wgsl: Vec<_> = storage.iter().map(|s| (s.0, s.1.as_str(), s.2)).collect();
    let rust: Vec<_> = (1..).zip(B::LAYOUT).map(|(i, &(n, a))| (i, n, a)).collect();
    if wgsl != rust {
        bad.push(format!("{file}: bindings {wgsl:?}, Rust {rust:?}"));
    }
    for (b, name, declared, written) in &storage {
        if *declared == Access::ReadWrite && !written {
            bad.push(format!(
                "{file}: binding {b} ({name}) is never written: declare it read"
            ));
        }
    }
    bad
}

/// The kernel modules: every WGSL file but the prelude and the shared parts, by name.
fn kernel_files() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_str().unwrap().to_string())
        .filter(|f| {
            f.ends_with(".wgsl")
                && f != "prelude.wgsl"
                && !super::WGSL_PARTS.iter().any(|(part, _)| part == f)
        })
        .collect();
    files.sort();
    files
}

#[test]
fn every_wgsl_file_validates_and_emits_spirv() {
    let mut n = 0;
    for file in kernel_files() {
        let (module, info) = parse(&file);
        // Override constants (workgroup sizes) at their defaults, as a pipeline without values.
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            &module,
            &info,
            None,
            &Default::default(),
        )
        .unwrap_or_else(|e| panic!("{file}: {e}"));
        let spv = naga::back::spv::write_vec(&module, &info, &Default::default(), None)
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(spv[0], 0x0723_0203, "{file}: SPIR-V magic");
        n += 1;
    }
    assert_eq!(n, 14, "the kernel modules in wgsl/");
}

#[test]
fn every_module_matches_its_rust_interface() {
    use super::{
        adjacency, assemble, assign, bounds, coarse, copy, grow, kmedoids_flat, kmedoids_parallel,
        kmedoids_parallel_moves, morton, scan, select,
    };
    let bad: Vec<String> = [
        interface::<adjacency::Params, adjacency::Buffers>("adjacency.wgsl"),
        interface::<assemble::Params, assemble::Buffers>("assemble.wgsl"),
        interface::<bounds::Params, bounds::Buffers>("bounds.wgsl"),
        interface::<copy::Params, copy::Buffers>("copy.wgsl"),
        interface::<grow::Params, grow::Buffers>("grow.wgsl"),
        interface::<morton::Params, morton::Buffers>("morton.wgsl"),
        interface::<coarse::Params, coarse::Buffers>("coarse.wgsl"),
        interface::<kmedoids_parallel::Params, kmedoids_parallel::Buffers>(
            "kmedoids_parallel.wgsl",
        ),
        interface::<kmedoids_parallel_moves::Params, kmedoids_parallel_moves::Buffers>(
            "kmedoids_parallel_moves.wgsl",
        ),
        interface::<assign::Params, kmedoids_flat::UpdateBuffers>("update.wgsl"),
        interface::<assign::Params, assign::AssignBuffers>("assign.wgsl"),
        interface::<assign::Params, kmedoids_flat::SplitBuffers>("split.wgsl"),
        interface::<scan::Params, scan::Buffers>("scan.wgsl"),
        interface::<select::Params, select::Buffers>("select.wgsl"),
    ]
    .concat();
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The value of the u32 constant `name` that `file` (behind the prelude) declares.
fn constant(file: &str, name: &str) -> u32 {
    let (module, _) = parse(file);
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("{name} in {file}"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => v,
        ref e => panic!("{file}: {name} is {e:?}"),
    }
}

#[test]
fn the_prelude_part_is_the_rust_part() {
    assert_eq!(constant("bounds.wgsl", "PART") as usize, super::PART);
}

#[test]
fn the_sort_block_is_the_drivers() {
    assert_eq!(
        constant("morton.wgsl", "BLOCK") as usize,
        super::morton::BLOCK
    );
}

#[test]
fn the_interface_check_catches_a_mismatch() {
    // A binding set with the update's names against assign.wgsl must fail, as must a wrong Params.
    use super::{assign, kmedoids_flat};
    assert!(!interface::<assign::Params, kmedoids_flat::UpdateBuffers>("assign.wgsl").is_empty());
    assert!(!interface::<super::scan::Params, assign::AssignBuffers>("assign.wgsl").is_empty());
}

#[test]
fn device_minimums_are_what_the_widest_kernels_use() {
    // Storage buffers per module (a family's bind group layout holds every binding its module
    // declares, and each of its pipelines uses that layout) and workgroup memory per entry point
    // (what the kernel uses), the most over every kernel.
    let (mut storage, mut workgroup) = (0u32, 0u32);
    for file in kernel_files() {
        let (module, info) = parse(&file);
        let declared = module
            .global_variables
            .iter()
            .filter(|(_, v)| matches!(v.space, naga::AddressSpace::Storage { .. }))
            .count() as u32;
        storage = storage.max(declared);
        for i in 0..module.entry_points.len() {
            let used = info.get_entry_point(i);
            let w: u32 = module
                .global_variables
                .iter()
                .filter(|(h, v)| v.space == naga::AddressSpace::WorkGroup && !used[*h].is_empty())
                .map(|(_, v)| module.types[v.ty].inner.size(module.to_ctx()))
                .sum();
            workgroup = workgroup.max(w);
        }
    }
    assert_eq!(storage, super::MIN_STORAGE_BUFFERS);
    assert!(
        workgroup <= super::MIN_WORKGROUP_STORAGE
            && super::MIN_WORKGROUP_STORAGE - workgroup < 1024,
        "the widest kernel uses {workgroup} bytes of workgroup memory"
    );
}

#[test]
fn the_prelude_fine_cell_bound_is_the_cpus() {
    assert_eq!(
        constant("kmedoids_parallel.wgsl", "FINE_MAX"),
        crate::strategy::kmedoids::morton::FINE_MAX
    );
}

#[test]
fn the_region_kernel_reads_the_rust_layout() {
    // The constants come from `parallel::layout` through build.rs, not a copy: each is the Rust
    // value, and the kernel declares none of them itself.
    use crate::strategy::kmedoids::parallel::layout::CONSTANTS;
    for &(name, value) in CONSTANTS {
        assert_eq!(constant("kmedoids_parallel.wgsl", name), value, "{name}");
    }
    let own = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl/kmedoids_parallel.wgsl"),
    )
    .unwrap();
    for &(name, _) in CONSTANTS {
        assert!(
            !own.contains(&format!("const {name}:")),
            "{name} is declared by hand"
        );
    }
}
