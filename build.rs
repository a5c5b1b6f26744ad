//! Compiles the GLSL in glsl/ to SPIR-V with glslangValidator (installed by `make setup`), every
//! variant that `render::interface::Shader::all` lists, after writing `interface.glsl` (the
//! bindings, flags and counter slots the shaders share with `render::pass`), and writes the list
//! of modules (`shaders.rs`, included by src/render/mod.rs). Without glslangValidator the build still
//! succeeds, with empty shader files: the render commands then say how to get it, and everything
//! else works. It also writes `kmedoids_parallel_layout.wgsl`: the constants and storage sections
//! that `kmedoids-parallel`'s CPU reference, GPU driver and kernel share, as WGSL.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

// The shader variants and the constants the GLSL shares with the Rust side, defined once.
#[allow(dead_code)]
#[path = "src/render/interface.rs"]
mod interface;

// Laced wires' bit layout, shared with the codec: the shaders include it as GLSL constants.
#[path = "src/compress/laced/layout.rs"]
#[allow(dead_code)] // Only the GLSL rendering is used here; the codec uses the rest.
mod laced_layout;

// kmedoids-parallel's shared constants and storage sections, emitted as WGSL for its kernel.
#[path = "src/strategy/kmedoids/parallel/layout.rs"]
#[allow(dead_code)] // Only the WGSL text is used here.
mod kmedoids_parallel_layout;

/// Writes `kmedoids_parallel_layout.wgsl` (put in front of `wgsl/kmedoids_parallel.wgsl` by the
/// `wgsl!` macro) into `out`.
fn write_kmedoids_parallel_layout(out: &Path) {
    println!("cargo:rerun-if-changed=src/strategy/kmedoids/parallel/layout.rs");
    std::fs::write(
        out.join("kmedoids_parallel_layout.wgsl"),
        kmedoids_parallel_layout::wgsl(),
    )
    .expect("write kmedoids_parallel_layout.wgsl");
}

/// Writes `laced_layout.glsl` (laced wires' record layout as GLSL constants, from the table the
/// encoder and decoder read) into `out`, which is on glslangValidator's include path.
fn write_laced_layout_header(out: &Path) {
    println!("cargo:rerun-if-changed=src/compress/laced/layout.rs");
    std::fs::write(out.join("laced_layout.glsl"), laced_layout::glsl())
        .expect("write laced_layout.glsl");
}

fn main() {
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    // results/ headers name the build: custom profiles (fuzz) are told apart by their settings.
    let opt = std::env::var("OPT_LEVEL").unwrap_or_default();
    println!("cargo:rustc-env=MESHLETLAB_OPT_LEVEL={opt}");
    println!("cargo:rerun-if-changed=glsl");
    println!("cargo:rerun-if-changed=src/render/interface.rs");
    write_kmedoids_parallel_layout(&out);
    // Only the `render` feature includes the shaders.
    if std::env::var_os("CARGO_FEATURE_RENDER").is_none() {
        return;
    }
    let glsl = Path::new("glsl");
    write_laced_layout_header(&out);
    let mut missing = false;
    // Included by glsl/common.glsl: bindings, flags, counter slots, the task group size.
    std::fs::write(out.join("interface.glsl"), interface::glsl_header())
        .expect("write interface.glsl");
    let mut table = String::from("/// Every compiled shader in `Shader::all()` order (SPIR-V bytes; empty when glslangValidator was missing).\npub const SHADERS: &[&[u8]] = &[\n");
    for shader in interface::Shader::all() {
        let (src, dst, defines) = (shader.source(), shader.spirv_file(), shader.defines());
        let target = out.join(&dst);
        let status = Command::new("glslangValidator")
            .args(["--target-env", "vulkan1.3"])
            .arg(format!("-I{}", out.display()))
            .arg("-o")
            .arg(&target)
            .args(&defines)
            .arg(glsl.join(src))
            .output();
        match status {
            Ok(o) if o.status.success() => {}
            Ok(o) => panic!(
                "glslangValidator failed on glsl/{src} ({}):\n{}{}",
                defines.join(" "),
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ),
            Err(_) => {
                missing = true;
                std::fs::write(&target, []).expect("write placeholder");
            }
        }
        writeln!(
            table,
            "    include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{dst}\")), // {}",
            shader.label()
        )
        .unwrap();
    }
    table.push_str("];\n");
    std::fs::write(out.join("shaders.rs"), table).expect("write shaders.rs");
    if missing {
        println!(
            "cargo:warning=glslangValidator not found: the mesh-shader render pass is disabled (run `make setup`)"
        );
        watch_for_compiler();
    } else if let Some(found) = find_in_path("glslangValidator") {
        // A new compiler version recompiles the shaders.
        println!("cargo:rerun-if-changed={}", found.display());
    }
}

/// Without the compiler the shader files are empty placeholders, and nothing in the crate changes
/// when `make setup` installs it later, so cargo would keep the broken build. Installing a program
/// adds an entry to a directory on PATH, which changes that directory's modification time: watching
/// every PATH directory reruns this script (and compiles the shaders) on the first build after the
/// compiler appears, with no file touched by hand. Watched only while the compiler is missing.
fn watch_for_compiler() {
    println!("cargo:rerun-if-env-changed=PATH");
    for dir in std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()) {
        if dir.is_dir() {
            println!("cargo:rerun-if-changed={}", dir.display());
        }
    }
}

/// The first `name` on PATH, as the shell would run it.
fn find_in_path(name: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
}
