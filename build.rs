//! Compiles the GLSL in glsl/ to SPIR-V with glslangValidator (installed by `make setup`). Without
//! it the build still succeeds, with empty shader files: the render commands then say how to get it,
//! and everything else works.

use std::path::{Path, PathBuf};
use std::process::Command;

/// (source, output, extra defines)
const SHADERS: &[(&str, &str, &[&str])] = &[
    ("meshlet.task", "meshlet.task.spv", &[]),
    (
        "meshlet.mesh",
        "meshlet_64_126.mesh.spv",
        &["-DMAX_V=64", "-DMAX_P=126"],
    ),
    (
        "meshlet.mesh",
        "meshlet_256_256.mesh.spv",
        &["-DMAX_V=256", "-DMAX_P=256"],
    ),
    ("baseline.vert", "baseline.vert.spv", &[]),
    ("shade.frag", "shade.frag.spv", &[]),
    ("meshlet_id.frag", "meshlet_id.frag.spv", &[]),
];

fn main() {
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let glsl = Path::new("glsl");
    println!("cargo:rerun-if-changed=glsl");
    let mut missing = false;
    for (src, dst, defines) in SHADERS {
        let target = out.join(dst);
        let status = Command::new("glslangValidator")
            .args(["--target-env", "vulkan1.3", "-o"])
            .arg(&target)
            .args(*defines)
            .arg(glsl.join(src))
            .output();
        match status {
            Ok(o) if o.status.success() => {}
            Ok(o) => panic!(
                "glslangValidator failed on glsl/{src}:\n{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ),
            Err(_) => {
                missing = true;
                std::fs::write(&target, []).expect("write placeholder");
            }
        }
    }
    if missing {
        println!(
            "cargo:warning=glslangValidator not found: the mesh-shader render pass is disabled (run `make setup`)"
        );
    }
}
