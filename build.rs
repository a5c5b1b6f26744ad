//! Compiles the GLSL in glsl/ to SPIR-V with glslangValidator (installed by `make setup`), one task
//! and two mesh shaders (64/126 and 256/256) per descriptor layout, and writes the list of modules
//! (`shaders.rs`, included by src/render/mod.rs). Without glslangValidator the build still
//! succeeds, with empty shader files: the render commands then say how to get it, and everything
//! else works.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

// Laced wires' bit layout, shared with the codec: the shaders include it as GLSL constants.
#[path = "src/compress/laced/layout.rs"]
#[allow(dead_code)] // Only the GLSL rendering is used here; the codec uses the rest.
mod laced_layout;

/// Descriptor layouts: (name, DESC value), as `meshlet::descriptor::Format`.
const FORMATS: &[(&str, u32)] = &[
    ("split", 0),
    ("nvidia-a", 1),
    ("nvidia-b", 2),
    ("monolithic", 3),
];

/// (module name, source, output file, defines)
fn shaders() -> Vec<(String, &'static str, String, Vec<String>)> {
    let mut list = Vec::new();
    for (fmt, id) in FORMATS {
        list.push((
            format!("meshlet.task ({fmt})"),
            "meshlet.task",
            format!("meshlet_{fmt}.task.spv"),
            vec![format!("-DDESC={id}")],
        ));
        for (v, p) in [(64, 126), (256, 256)] {
            list.push((
                format!("meshlet.mesh ({fmt}, {v}/{p})"),
                "meshlet.mesh",
                format!("meshlet_{fmt}_{v}_{p}.mesh.spv"),
                vec![
                    format!("-DDESC={id}"),
                    format!("-DMAX_V={v}"),
                    format!("-DMAX_P={p}"),
                ],
            ));
        }
    }
    // The cluster-LOD task shader (split layout only: LOD passes always upload split).
    list.push((
        "meshlet.task (split, lod)".to_string(),
        "meshlet.task",
        "meshlet_split_lod.task.spv".to_string(),
        vec!["-DDESC=0".to_string(), "-DLOD=1".to_string()],
    ));
    // Compressed formats (src/render/compressed.rs): the task shader with and without laced
    // wires' culling records, the laced-wires, SC and IX compact mesh shaders and the vertex
    // shader that pulls GI and TS compact corners.
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    list.push((
        "compressed.task (laced-wires)".into(),
        "compressed.task",
        "compressed_laced.task.spv".into(),
        s(&["-DLACED=1"]),
    ));
    list.push((
        "compressed.task".into(),
        "compressed.task",
        "compressed.task.spv".into(),
        vec![],
    ));
    for p in [126, 256] {
        // Scans in workgroup memory, and with subgroup operations where the device has them.
        for (tag, extra) in [("", None), (", subgroups", Some("-DSUBGROUPS=1"))] {
            let mut defines = vec![format!("-DMAX_P={p}")];
            defines.extend(extra.map(String::from));
            list.push((
                format!("laced.mesh (64/{p}{tag})"),
                "laced.mesh",
                format!(
                    "laced_{p}{}.mesh.spv",
                    if extra.is_some() { "_sg" } else { "" }
                ),
                defines,
            ));
        }
    }
    for (name, kind) in [("ix-compact", 1), ("sc-compact", 2)] {
        for (v, p) in [(64, 126), (256, 256)] {
            list.push((
                format!("compact.mesh ({name}, {v}/{p})"),
                "compact.mesh",
                format!("compact_{name}_{v}_{p}.mesh.spv"),
                vec![
                    format!("-DKIND={kind}"),
                    format!("-DMAX_V={v}"),
                    format!("-DMAX_P={p}"),
                ],
            ));
        }
    }
    for (name, kind) in [("ts-compact", 0), ("gi-compact", 3)] {
        list.push((
            format!("compact.vert ({name})"),
            "compact.vert",
            format!("compact_{name}.vert.spv"),
            vec![format!("-DKIND={kind}")],
        ));
    }
    for src in ["baseline.vert", "shade.frag", "meshlet_id.frag"] {
        list.push((src.to_string(), src, format!("{src}.spv"), vec![]));
    }
    list
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
    // Only the `render` feature includes the shaders.
    if std::env::var_os("CARGO_FEATURE_RENDER").is_none() {
        return;
    }
    let glsl = Path::new("glsl");
    write_laced_layout_header(&out);
    let mut missing = false;
    let mut table = String::from("/// Every compiled shader as (name, SPIR-V bytes; empty when glslangValidator was missing).\npub const SHADERS: &[(&str, &[u8])] = &[\n");
    for (name, src, dst, defines) in shaders() {
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
            "    ({name:?}, include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{dst}\"))),"
        )
        .unwrap();
    }
    table.push_str("];\n");
    std::fs::write(out.join("shaders.rs"), table).expect("write shaders.rs");
    if missing {
        println!(
            "cargo:warning=glslangValidator not found: the mesh-shader render pass is disabled (run `make setup`)"
        );
    }
}
