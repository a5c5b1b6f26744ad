//! Which codec: the one enum every compressed-meshlet user names (the tool's `--format`, the file,
//! the renderer), with its encode and decode dispatch.

use super::{baseline, laced, meshopt_codec, DecodeError, Decoded, Encoded};
use crate::mesh::Mesh;

/// A compressed-meshlet codec: meshoptimizer's, laced wires, or one of the paper's eight
/// comparison formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "tool", derive(clap::ValueEnum))]
pub enum Codec {
    /// meshoptimizer's meshlet codec with anchored per-axis positions (the peer).
    Meshopt,
    /// Laced wires (Mlakar et al. 2024): every vertex stored once, on its wire.
    LacedWires,
    /// Triangle soup, f32 corners.
    Ts,
    /// Triangle soup, quantised per meshlet.
    TsCompact,
    /// Indexed meshlets, 32-bit references, f32 global buffer.
    Ix,
    /// Indexed meshlets, packed references, quantised global buffer.
    IxCompact,
    /// Self-contained meshlets, f32 copies.
    Sc,
    /// Self-contained meshlets, quantised per meshlet.
    ScCompact,
    /// Global index buffer, 32-bit indices, f32 positions.
    Gi,
    /// Global index buffer, packed indices, quantised positions.
    GiCompact,
}

impl Codec {
    /// The number the compressed-meshlet file stores for it.
    #[cfg(feature = "io")]
    pub(crate) fn id(self) -> u32 {
        match self {
            Codec::Meshopt => 1,
            Codec::LacedWires => 2,
            f => 3 + Self::BASELINES.iter().position(|b| b.0 == f).unwrap_or(0) as u32,
        }
    }

    /// Every format.
    pub const ALL: [Codec; 10] = [
        Codec::Meshopt,
        Codec::LacedWires,
        Codec::Ts,
        Codec::TsCompact,
        Codec::Ix,
        Codec::IxCompact,
        Codec::Sc,
        Codec::ScCompact,
        Codec::Gi,
        Codec::GiCompact,
    ];

    /// The paper's comparison formats: (format, kind, compact).
    const BASELINES: [(Codec, baseline::Kind, bool); 8] = [
        (Codec::Ts, baseline::Kind::Ts, false),
        (Codec::TsCompact, baseline::Kind::Ts, true),
        (Codec::Ix, baseline::Kind::Ix, false),
        (Codec::IxCompact, baseline::Kind::Ix, true),
        (Codec::Sc, baseline::Kind::Sc, false),
        (Codec::ScCompact, baseline::Kind::Sc, true),
        (Codec::Gi, baseline::Kind::Gi, false),
        (Codec::GiCompact, baseline::Kind::Gi, true),
    ];

    /// The codec a compressed-meshlet file's number names.
    #[cfg(feature = "io")]
    pub(crate) fn from_id(id: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.id() == id)
    }

    /// The name on the command line (`--format`; clap's kebab-case of the variant, which a test
    /// checks).
    pub fn name(self) -> String {
        match self {
            Codec::Meshopt => "meshopt",
            Codec::LacedWires => "laced-wires",
            Codec::Ts => "ts",
            Codec::TsCompact => "ts-compact",
            Codec::Ix => "ix",
            Codec::IxCompact => "ix-compact",
            Codec::Sc => "sc",
            Codec::ScCompact => "sc-compact",
            Codec::Gi => "gi",
            Codec::GiCompact => "gi-compact",
        }
        .to_string()
    }

    /// The compact variant of a basic comparison format.
    pub fn compact(self) -> Option<Self> {
        match self {
            Codec::Ts => Some(Codec::TsCompact),
            Codec::Ix => Some(Codec::IxCompact),
            Codec::Sc => Some(Codec::ScCompact),
            Codec::Gi => Some(Codec::GiCompact),
            _ => None,
        }
    }

    /// Whether positions are stored exactly (f32), whatever the tolerance.
    pub fn exact(self) -> bool {
        matches!(self, Codec::Ts | Codec::Ix | Codec::Sc | Codec::Gi)
    }

    /// Encodes `ml` (meshlets of `mesh`) in this format with every position within `tolerance`.
    pub fn encode(
        self,
        mesh: &Mesh,
        ml: &crate::meshlet::Meshlets,
        tolerance: f64,
    ) -> Result<Encoded, super::EncodeError> {
        Ok(match self {
            Codec::Meshopt => meshopt_codec::encode(mesh, ml, tolerance)?,
            Codec::LacedWires => laced::encode(mesh, ml, tolerance)?,
            f => {
                let (_, kind, compact) = Self::BASELINES
                    .into_iter()
                    .find(|b| b.0 == f)
                    .expect("every other format is a baseline");
                baseline::encode(mesh, ml, tolerance, kind, compact)?
            }
        })
    }

    /// Decodes meshlet `i` of an encoding in this format. A position that decodes to NaN or an
    /// infinity (a damaged raw float in the basic formats, say) is an error, as in the mesh
    /// loaders: no valid file holds one.
    pub fn decode(self, enc: &Encoded, i: usize) -> Result<Decoded, DecodeError> {
        let d = match self {
            Codec::Meshopt => meshopt_codec::decode(enc, i),
            Codec::LacedWires => laced::decode(enc, i),
            _ => baseline::decode(enc, i),
        }?;
        if let Some(k) = d
            .positions
            .iter()
            .position(|p| !p.iter().all(|x| x.is_finite()))
        {
            return Err(DecodeError::Invalid {
                meshlet: i,
                what: format!("vertex {k} decodes to a non-finite position"),
            });
        }
        Ok(d)
    }
}
