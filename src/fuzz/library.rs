//! The `library` target: arrays instead of files. A case is the arrays an engine hands the crate
//! (positions, indices, limits, meshlets made elsewhere, a tolerance, a strategy and a codec
//! number) framed in one little-endian buffer, so the byte-level mutations of the file targets
//! apply to them unchanged: a flipped bit is a NaN coordinate, a header number an index far out of
//! range or a limit of 0, a duplicated chunk a meshlet whose range runs past its array.
//!
//! [`drive`] takes them through the public API an engine calls: the checked constructors
//! ([`Limits::new`], [`Mesh::from_slices`], [`Meshlets::new`]), then on what they accept a
//! strategy, the validator, the bounds, every descriptor layout, a codec (encoded and every
//! meshlet decoded) and the LOD build with a cut checked for cracks. Every step must return a value
//! or a typed error; a panic or an abort is a defect, as it is for the readers.
//!
//! **Framing** (all little-endian): `u32` max vertices, `u32` max triangles, `u32` strategy (an
//! index into [`Kind::ALL`], taken modulo its length), `u32` codec (into [`Codec::ALL`], likewise),
//! `f32` tolerance, then five arrays, each a `u32` count and its items: positions (3 x `f32`),
//! indices (`u32`), meshlets (4 x `u32`), meshlet vertices (`u32`), meshlet corners (`u8`). A
//! count beyond the bytes present takes the items that are there, so every buffer decodes: the
//! arrays, not the framing, are under test.

use crate::compress::Codec;
use crate::lod;
use crate::mesh::Mesh;
use crate::meshlet::{bounds, descriptor, validate, Limits, Meshlet, Meshlets};
use crate::strategy::{Kind, Options};

/// The name errors must start with (the "file" of a library case).
pub const LABEL: &str = "case.lib";

/// What a case hands the library.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Arrays {
    /// Limits, unchecked: (max vertices, max triangles).
    pub limits: (u32, u32),
    /// Strategy number (modulo [`Kind::ALL`]'s length).
    pub strategy: u32,
    /// Codec number (modulo [`Codec::ALL`]'s length).
    pub codec: u32,
    /// Codec tolerance.
    pub tolerance: f32,
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangle list.
    pub indices: Vec<u32>,
    /// Meshlets made elsewhere.
    pub meshlets: Vec<Meshlet>,
    /// Their global vertex indices.
    pub vertices: Vec<u32>,
    /// Their local corners.
    pub triangles: Vec<u8>,
}

/// Offsets of an encoded [`Arrays`], for the seed's mutation targets.
#[derive(Default)]
pub(crate) struct Layout {
    /// Where each `u32` header number and count sits.
    pub numbers: Vec<usize>,
    /// Where each `f32` sits (the tolerance and the coordinates).
    pub floats: Vec<usize>,
    /// Section starts.
    pub boundaries: Vec<usize>,
}

impl Arrays {
    /// The framed buffer, with its layout.
    pub(crate) fn encode(&self) -> (Vec<u8>, Layout) {
        let mut b = Vec::new();
        let mut l = Layout::default();
        let number = |b: &mut Vec<u8>, l: &mut Layout, x: u32| {
            l.numbers.push(b.len());
            b.extend(x.to_le_bytes());
        };
        number(&mut b, &mut l, self.limits.0);
        number(&mut b, &mut l, self.limits.1);
        number(&mut b, &mut l, self.strategy);
        number(&mut b, &mut l, self.codec);
        l.floats.push(b.len());
        b.extend(self.tolerance.to_le_bytes());
        l.boundaries.push(b.len());
        number(&mut b, &mut l, self.positions.len() as u32);
        for c in self.positions.iter().flatten() {
            l.floats.push(b.len());
            b.extend(c.to_le_bytes());
        }
        l.boundaries.push(b.len());
        number(&mut b, &mut l, self.indices.len() as u32);
        for &i in &self.indices {
            number(&mut b, &mut l, i);
        }
        l.boundaries.push(b.len());
        number(&mut b, &mut l, self.meshlets.len() as u32);
        for m in &self.meshlets {
            l.boundaries.push(b.len());
            for x in [
                m.vertex_offset,
                m.triangle_offset,
                m.vertex_count,
                m.triangle_count,
            ] {
                number(&mut b, &mut l, x);
            }
        }
        l.boundaries.push(b.len());
        number(&mut b, &mut l, self.vertices.len() as u32);
        b.extend(self.vertices.iter().flat_map(|v| v.to_le_bytes()));
        l.boundaries.push(b.len());
        number(&mut b, &mut l, self.triangles.len() as u32);
        b.extend_from_slice(&self.triangles);
        (b, l)
    }

    /// The arrays a buffer frames; never fails (see the module docs).
    pub fn decode(bytes: &[u8]) -> Arrays {
        let mut r = Cursor { bytes, at: 0 };
        let limits = (r.u32(), r.u32());
        let (strategy, codec) = (r.u32(), r.u32());
        let tolerance = f32::from_bits(r.u32());
        let positions = r.items(12, |c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        });
        let indices = r.items(4, |c| u32::from_le_bytes(c.try_into().unwrap()));
        let meshlets = r.items(16, |c| {
            let w = |k: usize| u32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap());
            Meshlet {
                vertex_offset: w(0),
                triangle_offset: w(1),
                vertex_count: w(2),
                triangle_count: w(3),
            }
        });
        let vertices = r.items(4, |c| u32::from_le_bytes(c.try_into().unwrap()));
        let triangles = r.items(1, |c| c[0]);
        Arrays {
            limits,
            strategy,
            codec,
            tolerance,
            positions,
            indices,
            meshlets,
            vertices,
            triangles,
        }
    }
}

/// Reads the framing; past the end every number is 0 and every array empty.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn u32(&mut self) -> u32 {
        let Some(c) = self.bytes.get(self.at..self.at + 4) else {
            self.at = self.bytes.len();
            return 0;
        };
        self.at += 4;
        u32::from_le_bytes(c.try_into().unwrap())
    }

    /// A count, then as many items of `size` bytes as it asks for and the bytes hold.
    fn items<T>(&mut self, size: usize, item: impl Fn(&[u8]) -> T) -> Vec<T> {
        let asked = self.u32() as usize;
        let there = (self.bytes.len() - self.at) / size;
        let n = asked.min(there);
        let out = self.bytes[self.at..self.at + n * size]
            .chunks_exact(size)
            .map(item)
            .collect();
        self.at += n * size;
        out
    }
}

/// Takes `a` through the library (see the module docs): `Ok(Valid)` when the constructors
/// accepted everything, `Ok(Error(kind))` for the first typed refusal, `Err` for a defect (an
/// output the validator or a round trip rejects, an error that does not name the input).
pub fn drive(a: &Arrays) -> Result<super::Outcome, String> {
    use super::Outcome;
    let Ok(limits) = Limits::new(a.limits.0, a.limits.1) else {
        return Ok(Outcome::Error("limits"));
    };
    let mesh = match Mesh::from_slices(&a.positions, &a.indices, LABEL) {
        Ok(m) => m,
        Err(e) if e.to_string().starts_with(LABEL) => {
            return Ok(Outcome::Error(super::kind_name(&e.kind)))
        }
        Err(e) => return Err(format!("error does not name the input: {e}")),
    };
    let codec = Codec::ALL[a.codec as usize % Codec::ALL.len()];
    let tolerance = a.tolerance as f64;
    // Meshlets made elsewhere: whatever the constructor accepts, every consumer takes.
    let theirs = Meshlets::new(
        &mesh,
        a.meshlets.clone(),
        a.vertices.clone(),
        a.triangles.clone(),
    );
    if let Ok(ml) = &theirs {
        consume(&mesh, ml, limits, codec, tolerance)?;
    }
    let kind = Kind::ALL[a.strategy as usize % Kind::ALL.len()];
    let ml = kind.strategy(&Options::default()).build(&mesh, limits);
    validate(&mesh, &ml, limits).map_err(|e| format!("{}: {e}", kind.name()))?;
    consume(&mesh, &ml, limits, codec, tolerance)?;
    let strategy = Kind::Meshopt.strategy(&Options::default());
    let dag = lod::build(&mesh, strategy.as_ref(), limits, &lod::Config::default());
    let (lo, hi) = mesh.bounding_box();
    let eye = hi + (hi - lo);
    if eye.is_finite() {
        let view = lod::select::View::new(eye, 1080.0, 1.0, 1.0);
        let cut = lod::select::select_cut(&dag, &view, 0);
        lod::select::check_cut(&dag, &cut, 0).map_err(|e| format!("LOD cut: {e}"))?;
    }
    Ok(match theirs {
        Ok(_) => Outcome::Valid,
        Err(_) => Outcome::Error("meshlets"),
    })
}

/// The consumers of a mesh's meshlets: the validator, bounds, every descriptor layout, and a codec
/// whose encoding must decode.
fn consume(
    mesh: &Mesh,
    ml: &Meshlets,
    limits: Limits,
    codec: Codec,
    tolerance: f64,
) -> Result<(), String> {
    let _ = validate(mesh, ml, limits);
    let b = bounds::compute_bounds(mesh, ml);
    if b.len() != ml.len() {
        return Err(format!("{} bounds for {} meshlets", b.len(), ml.len()));
    }
    for f in descriptor::DescriptorFormat::ALL {
        let _ = descriptor::pack(mesh, ml, f);
    }
    if let Ok(enc) = codec.encode(mesh, ml, tolerance) {
        for i in 0..ml.len() {
            let d = codec.decode(&enc, i).map_err(|e| {
                format!(
                    "{}: meshlet {i} encoded but does not decode: {e}",
                    codec.name()
                )
            })?;
            if d.triangles.len() != ml.meshlets()[i].triangle_count as usize {
                return Err(format!(
                    "{}: meshlet {i} decodes to another triangle count",
                    codec.name()
                ));
            }
        }
    }
    Ok(())
}

/// The seed cases: the corpus grid with meshlets of two strategies at two limits, one case per
/// strategy and codec pair spread over them.
pub(crate) fn seeds(mesh: &Mesh) -> Vec<(String, Vec<u8>, Layout)> {
    let mut out = Vec::new();
    for (strategy, (v, t)) in [("meshopt", (16u32, 12u32)), ("greedy", (8, 6))] {
        let limits = Limits::new(v, t).expect("valid seed limits");
        let s = crate::strategy::by_name(strategy, &Options::default()).expect("known strategy");
        let (meshlets, vertices, triangles) = s.build(mesh, limits).into_parts();
        let arrays = Arrays {
            limits: (v, t),
            strategy: out.len() as u32 * 7,
            codec: out.len() as u32 * 3,
            tolerance: 1e-3,
            positions: mesh.positions().to_vec(),
            indices: mesh.indices().to_vec(),
            meshlets,
            vertices,
            triangles,
        };
        let (bytes, layout) = arrays.encode();
        out.push((format!("library/{strategy}-{v}-{t}"), bytes, layout));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_survive_the_framing_and_any_cut() {
        let mesh = crate::mesh::generate::terrain(4, 1);
        for (name, bytes, layout) in seeds(&mesh) {
            let a = Arrays::decode(&bytes);
            assert_eq!(a.encode().0, bytes, "{name}");
            assert_eq!(a.positions, mesh.positions(), "{name}");
            assert_eq!(drive(&a), Ok(super::super::Outcome::Valid), "{name}");
            assert!(layout.numbers.len() > 8 && layout.floats.len() > 3);
            for cut in 0..bytes.len() {
                let short = Arrays::decode(&bytes[..cut]);
                assert!(short.positions.len() <= a.positions.len());
                drive(&short).unwrap();
            }
        }
    }
}
