//! Published figures of the seed paper, printed beside ours: Jensen, Frisvad, Bærentzen,
//! "Performance Comparison of Meshlet Generation Strategies", JCGT 12(2), 2023. Bunny, 64/126,
//! measured by the authors on their machine (not ours): Table 4 (processing time), Table 7 (meshlet
//! count), Table 8 (primitive fill). The paper's bunny has 69,666 triangles (its fills equal
//! 69,666 / (count x 126)); the shared bunny has 69,451.

/// One strategy's published Bunny figures; `None` where the paper gives none.
#[derive(Clone, Copy, Debug)]
pub struct PaperBunny {
    /// The paper's name for the strategy.
    pub paper_name: &'static str,
    /// Our strategy that corresponds to it, if we have it yet.
    pub ours: &'static str,
    /// Table 4: processing time in ms.
    pub time_ms: Option<f64>,
    /// Table 7: meshlet count.
    pub meshlets: Option<u32>,
    /// Table 8: primitive fill.
    pub primitive_fill: Option<f64>,
}

/// The paper's Bunny rows, in its order.
pub const BUNNY: &[PaperBunny] = &[
    PaperBunny {
        paper_name: "NVIDIA + tipsify",
        ours: "nvidia+tipsify",
        time_ms: Some(13.54),
        meshlets: Some(762),
        primitive_fill: Some(0.725),
    },
    PaperBunny {
        paper_name: "Kapoulkine (meshoptimizer)",
        ours: "meshopt",
        time_ms: Some(46.86),
        meshlets: Some(740),
        primitive_fill: None,
    },
    PaperBunny {
        paper_name: "Greedy",
        ours: "greedy",
        time_ms: Some(133.6),
        meshlets: Some(756),
        primitive_fill: Some(0.731),
    },
    PaperBunny {
        paper_name: "Bounding sphere",
        ours: "bsphere",
        time_ms: Some(255.1),
        meshlets: Some(731),
        primitive_fill: Some(0.756),
    },
    PaperBunny {
        paper_name: "k-medoids",
        ours: "kmedoids",
        time_ms: Some(50_769.0),
        meshlets: Some(921),
        primitive_fill: Some(0.600),
    },
];

/// The paper's row for one of our strategies; a `-paper` variant (the published code's behaviour,
/// e.g. `greedy-paper`) answers to the same row.
pub fn bunny_row(ours: &str) -> Option<&'static PaperBunny> {
    let base = ours.strip_suffix("-paper").unwrap_or(ours);
    BUNNY.iter().find(|r| r.ours == base)
}
