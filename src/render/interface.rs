//! The render pass's interface with its shaders, defined once: the storage bindings, the
//! push-constant flags, the counter slots and the shader variants. build.rs includes this file
//! (`#[path]`) to write `interface.glsl`, which every GLSL file gets through `common.glsl`, and to
//! compile every [`Shader`]; `pass.rs` binds, flags, reads and looks shaders up through the same
//! items, so a number can no longer disagree between the two sides.
//!
//! Self-contained on purpose (no `crate::` paths): build.rs compiles it on its own.

/// Storage bindings of descriptor set 0, in binding order (the GLSL names them `BINDING_<NAME>`
/// in upper case).
pub const BINDINGS: [&str; 12] = [
    // f32 x 3 per vertex (also the baseline's vertex buffer).
    "positions",
    // Meshlet descriptors, or a compressed format's per-meshlet offsets.
    "descriptors",
    // The descriptor layout's data words, or the compressed stream.
    "data",
    // Packed triangles, or a compressed format's first-triangle table.
    "triangles",
    // Per-meshlet culling data the task shader reads (bounding sphere, cone).
    "task",
    // The task shader's counters (`COUNTER_*`), then a LOD pass's drawn-meshlet bitmap.
    "counters",
    // A LOD pass's per-meshlet records (`lod::flat::Record`).
    "lod_records",
    // A LOD pass's view (`lod::flat::ViewData`).
    "lod_view",
    // Instanced passes: per instance, object-to-world rows, world-to-object rows and its largest
    // stretch (`render::pass::InstanceRecord`).
    "instances",
    // Occlusion culling: one word per (instance, meshlet) slot, 1 where it was visible in the
    // last frame.
    "visibility",
    // Occlusion culling: the depth pyramid, levels end to end (`PYRAMID_*`).
    "pyramid",
    // Exactness checks: per pixel, the least (depth bits << 32 | slot) of every fragment drawn.
    "ids",
];

/// Binding of `name` in [`BINDINGS`] (a build-time constant where used in consts).
pub const fn binding(name: &str) -> u32 {
    let mut i = 0;
    while i < BINDINGS.len() {
        if str_eq(BINDINGS[i], name) {
            return i as u32;
        }
        i += 1;
    }
    panic!("no such binding")
}

const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Push-constant `flags`: the task shader culls by the bounding sphere against the frustum.
pub const FLAG_FRUSTUM: u32 = 1 << 0;
/// Push-constant `flags`: the task shader culls by the normal cone.
pub const FLAG_CONE: u32 = 1 << 1;
/// Push-constant `flags`: `shade.frag` writes plain white (coverage and depth only).
pub const FLAG_UNLIT: u32 = 1 << 2;
/// Push-constant `flags`: the LOD task shader records each drawn meshlet's bit after the counters.
pub const FLAG_RECORD_IDS: u32 = 1 << 3;
/// Push-constant `flags`: positions and bounds are in the object space of instance
/// `pc.instance` (an instanced pass); without it they are world positions.
pub const FLAG_INSTANCED: u32 = 1 << 4;
/// Push-constant `flags`: the early phase of occlusion culling (draw what was visible last
/// frame, after the frustum and cone tests).
pub const FLAG_EARLY: u32 = 1 << 5;
/// Push-constant `flags`: the late phase (test everything against the pyramid, draw what is
/// newly visible, record every meshlet's visibility for the next frame).
pub const FLAG_LATE: u32 = 1 << 6;
/// Push-constant `flags`, for the tests only: read one pyramid texel (level 0, at the
/// footprint's centre) instead of the 2 x 2 that cover it, so the test is no longer conservative.
pub const FLAG_PYRAMID_ONE_TEXEL: u32 = 1 << 7;

/// Push-constant `flags`: a one-phase frame (frustum and cone only) that still records every
/// slot's visibility, for the frames where occlusion culling is skipped because it did not pay.
pub const FLAG_KEEP_VISIBILITY: u32 = 1 << 8;

/// The image the pass renders (`render::WIDTH` x `render::HEIGHT`; a test checks they agree).
pub const IMAGE_WIDTH: u32 = 1280;
/// See [`IMAGE_WIDTH`].
pub const IMAGE_HEIGHT: u32 = 720;
/// Samples per pixel (4x MSAA).
pub const IMAGE_SAMPLES: u32 = 4;
/// Levels of the depth pyramid: level 0 is the image, each next one half as wide and high
/// (rounded up), down to 1 x 1.
pub const PYRAMID_LEVELS: u32 = 12;

/// Counter slot: meshlets culled by the frustum.
pub const COUNTER_CULLED_FRUSTUM: usize = 0;
/// Counter slot: meshlets culled by the normal cone.
pub const COUNTER_CULLED_CONE: usize = 1;
/// Counter slot: meshlets drawn.
pub const COUNTER_DRAWN: usize = 2;
/// Counter slot: triangles in the meshlets culled by the frustum.
pub const COUNTER_TRIANGLES_FRUSTUM: usize = 3;
/// Counter slot: triangles in the meshlets culled by the cone.
pub const COUNTER_TRIANGLES_CONE: usize = 4;
/// Counter slot: LOD meshlets loaded but not on the cut.
pub const COUNTER_NOT_SELECTED: usize = 5;
/// Counter slot: meshlets the late phase found hidden behind the pyramid.
pub const COUNTER_OCCLUDED: usize = 6;
/// Counter slot: their triangles.
pub const COUNTER_TRIANGLES_OCCLUDED: usize = 7;
/// Counter slot: triangles in the meshlets drawn (both phases).
pub const COUNTER_TRIANGLES_DRAWN: usize = 8;
/// Counter slot: meshlets the late phase drew.
pub const COUNTER_DRAWN_LATE: usize = 9;
/// Counter slot: their triangles.
pub const COUNTER_TRIANGLES_DRAWN_LATE: usize = 10;
/// Counter slot: instances the late phase found wholly hidden behind the pyramid.
pub const COUNTER_INSTANCES_OCCLUDED: usize = 11;
/// Counter words before the drawn-meshlet bitmap (slots 12 to 15 are spare).
pub const COUNTER_WORDS: usize = 16;

/// Meshlets per task workgroup (one task invocation each).
pub const TASK_GROUP: u32 = 32;

/// The GLSL header with every constant above (written by build.rs into `interface.glsl`).
pub fn glsl_header() -> String {
    let mut s = String::from(
        "// Generated by build.rs from src/render/interface.rs: do not edit.\n\
         #ifndef INTERFACE_GLSL\n#define INTERFACE_GLSL\n",
    );
    for (i, name) in BINDINGS.iter().enumerate() {
        s += &format!("#define BINDING_{} {i}\n", name.to_uppercase());
    }
    let flags = [
        ("FLAG_FRUSTUM", FLAG_FRUSTUM),
        ("FLAG_CONE", FLAG_CONE),
        ("FLAG_UNLIT", FLAG_UNLIT),
        ("FLAG_RECORD_IDS", FLAG_RECORD_IDS),
        ("FLAG_INSTANCED", FLAG_INSTANCED),
        ("FLAG_EARLY", FLAG_EARLY),
        ("FLAG_LATE", FLAG_LATE),
        ("FLAG_PYRAMID_ONE_TEXEL", FLAG_PYRAMID_ONE_TEXEL),
        ("FLAG_KEEP_VISIBILITY", FLAG_KEEP_VISIBILITY),
        ("IMAGE_WIDTH", IMAGE_WIDTH),
        ("IMAGE_HEIGHT", IMAGE_HEIGHT),
        ("IMAGE_SAMPLES", IMAGE_SAMPLES),
        ("PYRAMID_LEVELS", PYRAMID_LEVELS),
    ];
    for (name, v) in flags {
        s += &format!("const uint {name} = {v}u;\n");
    }
    let counters = [
        ("COUNTER_CULLED_FRUSTUM", COUNTER_CULLED_FRUSTUM),
        ("COUNTER_CULLED_CONE", COUNTER_CULLED_CONE),
        ("COUNTER_DRAWN", COUNTER_DRAWN),
        ("COUNTER_TRIANGLES_FRUSTUM", COUNTER_TRIANGLES_FRUSTUM),
        ("COUNTER_TRIANGLES_CONE", COUNTER_TRIANGLES_CONE),
        ("COUNTER_NOT_SELECTED", COUNTER_NOT_SELECTED),
        ("COUNTER_OCCLUDED", COUNTER_OCCLUDED),
        ("COUNTER_TRIANGLES_OCCLUDED", COUNTER_TRIANGLES_OCCLUDED),
        ("COUNTER_TRIANGLES_DRAWN", COUNTER_TRIANGLES_DRAWN),
        ("COUNTER_DRAWN_LATE", COUNTER_DRAWN_LATE),
        ("COUNTER_TRIANGLES_DRAWN_LATE", COUNTER_TRIANGLES_DRAWN_LATE),
        ("COUNTER_INSTANCES_OCCLUDED", COUNTER_INSTANCES_OCCLUDED),
        ("COUNTER_WORDS", COUNTER_WORDS),
    ];
    for (name, v) in counters {
        s += &format!("const uint {name} = {v}u;\n");
    }
    // A macro, so layout(local_size_x = TASK_GROUP) can use it.
    s += &format!("#define TASK_GROUP {TASK_GROUP}\n#endif\n");
    s
}

/// Descriptor layouts the meshlet shaders read (`DESC` in glsl/descriptors.glsl), as
/// `meshlet::descriptor::DescriptorFormat`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Separate vertex and triangle streams.
    Split = 0,
    /// NVIDIA's layout A.
    NvidiaA = 1,
    /// NVIDIA's layout B.
    NvidiaB = 2,
    /// One block per meshlet.
    Monolithic = 3,
}

/// The compact formats the shaders decode (`KIND` in glsl/compact.*).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compact {
    /// Triangle soup, quantised per meshlet (vertex shader).
    Ts = 0,
    /// Indexed meshlets, packed references (mesh shader).
    Ix = 1,
    /// Self-contained meshlets, quantised (mesh shader).
    Sc = 2,
    /// Global index buffer, packed (vertex shader).
    Gi = 3,
}

/// Meshlet limits a mesh shader is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// 64 vertices, 126 triangles (the default limits).
    Small,
    /// 256 vertices, 256 triangles (anything larger).
    Large,
}

impl Size {
    /// (vertices, triangles).
    pub const fn limits(self) -> (u32, u32) {
        match self {
            Size::Small => (64, 126),
            Size::Large => (256, 256),
        }
    }
}

/// Every compiled shader variant: the GLSL file and the defines it is compiled with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shader {
    /// `meshlet.task` for a descriptor layout.
    MeshletTask(Layout),
    /// `meshlet.mesh` for a descriptor layout and size.
    MeshletMesh(Layout, Size),
    /// The cluster-LOD task shader (split layout: LOD passes always upload split).
    LodTask,
    /// `compressed.task`, with laced wires' culling records or without.
    CompressedTask {
        /// Laced wires (culls from the records).
        laced: bool,
    },
    /// `laced.mesh` (64 vertices) for 126 or 256 triangles, with subgroup scans or without.
    LacedMesh {
        /// At most 126 triangles.
        small: bool,
        /// Scans with subgroup operations (else workgroup memory).
        subgroups: bool,
    },
    /// `compact.mesh` for IX or SC compact.
    CompactMesh(Compact, Size),
    /// `compact.vert` for TS or GI compact.
    CompactVert(Compact),
    /// The vertex-pipeline baseline.
    BaselineVert,
    /// Flat shading.
    ShadeFrag,
    /// Colour by meshlet id.
    MeshletIdFrag,
    /// The exactness check's fragment shader: per pixel, the least (depth, slot) drawn.
    DepthIdFrag,
    /// The depth pyramid's compute shader.
    PyramidComp,
}

const LAYOUTS: [Layout; 4] = [
    Layout::Split,
    Layout::NvidiaA,
    Layout::NvidiaB,
    Layout::Monolithic,
];

impl Layout {
    /// The name (as `meshlet::descriptor::DescriptorFormat` displays it).
    pub const fn name(self) -> &'static str {
        match self {
            Layout::Split => "split",
            Layout::NvidiaA => "nvidia-a",
            Layout::NvidiaB => "nvidia-b",
            Layout::Monolithic => "monolithic",
        }
    }
}

impl Compact {
    /// The format's name (as `compress::Codec` names it).
    pub const fn name(self) -> &'static str {
        match self {
            Compact::Ts => "ts-compact",
            Compact::Ix => "ix-compact",
            Compact::Sc => "sc-compact",
            Compact::Gi => "gi-compact",
        }
    }
}

impl Shader {
    /// Every variant, in the order build.rs compiles them and `SHADERS` holds them.
    pub fn all() -> Vec<Shader> {
        let mut v = Vec::new();
        for l in LAYOUTS {
            v.push(Shader::MeshletTask(l));
            v.extend([Size::Small, Size::Large].map(|s| Shader::MeshletMesh(l, s)));
        }
        v.push(Shader::LodTask);
        v.extend([true, false].map(|laced| Shader::CompressedTask { laced }));
        for small in [true, false] {
            for subgroups in [false, true] {
                v.push(Shader::LacedMesh { small, subgroups });
            }
        }
        for c in [Compact::Ix, Compact::Sc] {
            v.extend([Size::Small, Size::Large].map(|s| Shader::CompactMesh(c, s)));
        }
        v.extend([Compact::Ts, Compact::Gi].map(Shader::CompactVert));
        v.extend([
            Shader::BaselineVert,
            Shader::ShadeFrag,
            Shader::MeshletIdFrag,
            Shader::DepthIdFrag,
            Shader::PyramidComp,
        ]);
        v
    }

    /// Position in [`Shader::all`].
    pub fn index(self) -> usize {
        Shader::all()
            .iter()
            .position(|&s| s == self)
            .expect("every variant is in all()")
    }

    /// The GLSL file in glsl/.
    pub fn source(self) -> &'static str {
        match self {
            Shader::MeshletTask(_) | Shader::LodTask => "meshlet.task",
            Shader::MeshletMesh(..) => "meshlet.mesh",
            Shader::CompressedTask { .. } => "compressed.task",
            Shader::LacedMesh { .. } => "laced.mesh",
            Shader::CompactMesh(..) => "compact.mesh",
            Shader::CompactVert(_) => "compact.vert",
            Shader::BaselineVert => "baseline.vert",
            Shader::ShadeFrag => "shade.frag",
            Shader::MeshletIdFrag => "meshlet_id.frag",
            Shader::DepthIdFrag => "depth_id.frag",
            Shader::PyramidComp => "pyramid.comp",
        }
    }

    /// The glslangValidator defines.
    pub fn defines(self) -> Vec<String> {
        let size = |s: Size| {
            let (v, p) = s.limits();
            [format!("-DMAX_V={v}"), format!("-DMAX_P={p}")]
        };
        match self {
            Shader::MeshletTask(l) => vec![format!("-DDESC={}", l as u32)],
            Shader::MeshletMesh(l, s) => {
                let mut d = vec![format!("-DDESC={}", l as u32)];
                d.extend(size(s));
                d
            }
            Shader::LodTask => vec!["-DDESC=0".into(), "-DLOD=1".into()],
            Shader::CompressedTask { laced } => {
                if laced {
                    vec!["-DLACED=1".into()]
                } else {
                    vec![]
                }
            }
            Shader::LacedMesh { small, subgroups } => {
                let mut d = vec![format!("-DMAX_P={}", if small { 126 } else { 256 })];
                if subgroups {
                    d.push("-DSUBGROUPS=1".into());
                }
                d
            }
            Shader::CompactMesh(c, s) => {
                let mut d = vec![format!("-DKIND={}", c as u32)];
                d.extend(size(s));
                d
            }
            Shader::CompactVert(c) => vec![format!("-DKIND={}", c as u32)],
            Shader::BaselineVert
            | Shader::ShadeFrag
            | Shader::MeshletIdFrag
            | Shader::DepthIdFrag
            | Shader::PyramidComp => vec![],
        }
    }

    /// A readable name for errors and the SPIR-V file name's stem, e.g. `meshlet.mesh (split, 64/126)`.
    pub fn label(self) -> String {
        let size = |s: Size| {
            let (v, p) = s.limits();
            format!("{v}/{p}")
        };
        match self {
            Shader::MeshletTask(l) => format!("meshlet.task ({})", l.name()),
            Shader::MeshletMesh(l, s) => format!("meshlet.mesh ({}, {})", l.name(), size(s)),
            Shader::LodTask => "meshlet.task (split, lod)".into(),
            Shader::CompressedTask { laced: true } => "compressed.task (laced-wires)".into(),
            Shader::CompressedTask { laced: false } => "compressed.task".into(),
            Shader::LacedMesh { small, subgroups } => format!(
                "laced.mesh (64/{}{})",
                if small { 126 } else { 256 },
                if subgroups { ", subgroups" } else { "" }
            ),
            Shader::CompactMesh(c, s) => format!("compact.mesh ({}, {})", c.name(), size(s)),
            Shader::CompactVert(c) => format!("compact.vert ({})", c.name()),
            Shader::BaselineVert
            | Shader::ShadeFrag
            | Shader::MeshletIdFrag
            | Shader::DepthIdFrag
            | Shader::PyramidComp => self.source().into(),
        }
    }

    /// The SPIR-V file build.rs writes in OUT_DIR.
    pub fn spirv_file(self) -> String {
        format!("shader_{:02}.spv", self.index())
    }
}
