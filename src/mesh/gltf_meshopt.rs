//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views whose bytes are stored in
//! meshoptimizer's vertex and index codecs (what `gltfpack -c` and `gltf-transform meshopt` write).
//!
//! A compressed view names a range of some buffer holding the encoded stream, and the shape of what
//! it decodes to: `count` elements of `byteStride` bytes in one of three modes (ATTRIBUTES: the
//! vertex codec, then an optional filter; TRIANGLES: the index-buffer codec; INDICES: the
//! index-sequence codec). The decoded bytes stand in for the view's own range, which lives in a
//! *fallback* buffer that may hold no data at all (`"fallback": true`, no URI): the extension lets a
//! reader that decodes ignore it, and so we do, even where a fallback file exists.
//!
//! Decoding is meshoptimizer's own (the `meshopt` crate, meshoptimizer 1.3), whose decoders are
//! documented as safe on untrusted input. Its C functions *assert* on a stride or count outside
//! their contract, so every such field is checked here first, and the decoded size is counted
//! against the caller's budget before anything is allocated: a few bytes of stream can announce any
//! `count`.
//!
//! The two extensions share this bitstream and JSON layout; the KHR one adds the COLOR filter
//! and the version-1 vertex codec, both of which meshoptimizer 1.3 decodes.

use super::error::{parse_err, MeshErrorKind};
use serde::Deserialize;

/// The two names of the extension, on buffer views and on fallback buffers.
pub const EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// The extension object on a buffer view (glTF names, camelCase).
#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct CompressedView {
    /// Buffer holding the encoded stream.
    pub buffer: usize,
    /// Offset of the stream in that buffer.
    #[serde(default)]
    pub byte_offset: u64,
    /// Length of the stream.
    pub byte_length: u64,
    /// Size of one decoded element.
    pub byte_stride: u64,
    /// Number of decoded elements.
    pub count: u64,
    /// Codec of the stream.
    pub mode: Mode,
    /// Filter applied after the vertex codec (ATTRIBUTES only).
    #[serde(default)]
    pub filter: Filter,
}

/// The codec a compressed view uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub enum Mode {
    /// Vertex attributes: meshoptimizer's vertex codec.
    Attributes,
    /// Triangle-list indices: the index-buffer codec.
    Triangles,
    /// Any index sequence: the index-sequence codec.
    Indices,
}

/// The filter that turns decoded attribute words into their final values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub enum Filter {
    /// Bytes as decoded.
    #[default]
    None,
    /// Octahedral unit vectors (normals, tangents), 4 or 8 bytes.
    Octahedral,
    /// Quaternions with a dropped largest component, 8 bytes.
    Quaternion,
    /// Floats as 8-bit exponent and 24-bit mantissa, any multiple of 4 bytes.
    Exponential,
    /// YCoCg colours (KHR only), 4 or 8 bytes.
    Color,
}

/// The compressed-view object of a buffer view's `extensions`, if it has one (an unreadable object
/// is an error: it would otherwise be read as the fallback's bytes).
pub fn compressed_view(
    others: &serde_json::Map<String, serde_json::Value>,
    loc: &str,
) -> Result<Option<CompressedView>, MeshErrorKind> {
    for name in EXTENSIONS {
        if let Some(v) = others.get(name) {
            return CompressedView::deserialize(v)
                .map(Some)
                .map_err(|e| parse_err(loc, format!("{name}: {e}")));
        }
    }
    Ok(None)
}

/// Whether a buffer's `extensions` mark it as a fallback (its bytes need not exist).
pub fn is_fallback(others: &serde_json::Map<String, serde_json::Value>) -> bool {
    EXTENSIONS.iter().any(|name| {
        others
            .get(*name)
            .and_then(|e| e.get("fallback"))
            .and_then(|f| f.as_bool())
            == Some(true)
    })
}

impl CompressedView {
    /// Bytes the view decodes to, once its stride and count have been checked against the codec's
    /// contract (what meshoptimizer would otherwise assert on).
    pub fn decoded_len(&self, loc: &str) -> Result<u64, MeshErrorKind> {
        let s = self.byte_stride;
        let ok = match self.mode {
            Mode::Attributes => s > 0 && s <= 256 && s.is_multiple_of(4),
            Mode::Triangles | Mode::Indices => s == 2 || s == 4,
        };
        if !ok {
            return Err(parse_err(
                loc,
                format!("byteStride {s} is not valid for mode {:?}", self.mode),
            ));
        }
        if self.mode == Mode::Triangles && !self.count.is_multiple_of(3) {
            return Err(parse_err(
                loc,
                format!("TRIANGLES count {} is not a multiple of 3", self.count),
            ));
        }
        let filter_ok = match (self.mode, self.filter) {
            (_, Filter::None) => true,
            (Mode::Attributes, Filter::Octahedral | Filter::Color) => s == 4 || s == 8,
            (Mode::Attributes, Filter::Quaternion) => s == 8,
            (Mode::Attributes, Filter::Exponential) => true,
            _ => false,
        };
        if !filter_ok {
            return Err(parse_err(
                loc,
                format!(
                    "filter {:?} does not apply to mode {:?} with byteStride {s}",
                    self.filter, self.mode
                ),
            ));
        }
        self.count
            .checked_mul(s)
            .ok_or_else(|| parse_err(loc, format!("count {} overflows", self.count)))
    }

    /// Decodes `stream` (the view's encoded bytes) into `count * byteStride` bytes, in 4-byte words
    /// so the filters see aligned elements. Call [`Self::decoded_len`] first: the caller budgets
    /// the size.
    pub fn decode(&self, stream: &[u8], loc: &str) -> Result<Vec<u32>, MeshErrorKind> {
        let len = self.decoded_len(loc)? as usize;
        let count = self.count as usize;
        let stride = self.byte_stride as usize;
        let corrupt = |code: String| {
            parse_err(
                loc,
                format!("{:?} stream does not decode ({code})", self.mode),
            )
        };
        let mut words = vec![0u32; len.div_ceil(4)];
        match self.mode {
            Mode::Attributes => {
                // SAFETY: `words` holds `count * stride` bytes (len.div_ceil(4) words); the stride
                // is a multiple of 4 in 4..=256 (checked by decoded_len), which is the decoder's
                // whole contract; it reads at most `stream.len()` bytes of `stream`.
                let rc = unsafe {
                    meshopt::ffi::meshopt_decodeVertexBuffer(
                        words.as_mut_ptr().cast(),
                        count,
                        stride,
                        stream.as_ptr(),
                        stream.len(),
                    )
                };
                if rc != 0 {
                    return Err(corrupt(format!("meshoptimizer error {rc}")));
                }
                self.unfilter(&mut words);
            }
            Mode::Triangles | Mode::Indices => {
                let bytes: &mut [u8] = &mut bytemuck::cast_slice_mut(&mut words)[..len];
                let triangles = self.mode == Mode::Triangles;
                match stride {
                    2 => decode_indices::<u16>(stream, count, triangles, bytes),
                    _ => decode_indices::<u32>(stream, count, triangles, bytes),
                }
                .map_err(|e| corrupt(e.to_string()))?;
            }
        }
        Ok(words)
    }

    /// Applies the filter in place (meshoptimizer's own filter decoders).
    fn unfilter(&self, words: &mut [u32]) {
        let (count, stride) = (self.count as usize, self.byte_stride as usize);
        let f = match self.filter {
            Filter::None => return,
            Filter::Octahedral => meshopt::ffi::meshopt_decodeFilterOct,
            Filter::Quaternion => meshopt::ffi::meshopt_decodeFilterQuat,
            Filter::Exponential => meshopt::ffi::meshopt_decodeFilterExp,
            Filter::Color => meshopt::ffi::meshopt_decodeFilterColor,
        };
        // SAFETY: `words` holds `count` elements of `stride` bytes, 4-byte aligned; decoded_len
        // checked the stride each filter accepts (what the C code asserts).
        unsafe { f(words.as_mut_ptr().cast(), count, stride) };
    }
}

/// Decodes `count` indices of type `T` (TRIANGLES: the index-buffer codec; else the
/// index-sequence codec) into `out`.
fn decode_indices<T: meshopt::encoding::IndexType + bytemuck::Pod>(
    stream: &[u8],
    count: usize,
    triangles: bool,
    out: &mut [u8],
) -> meshopt::Result<()> {
    let v: Vec<T> = match triangles {
        true => meshopt::decode_index_buffer(stream, count)?,
        false => meshopt::decode_index_sequence(stream, count)?,
    };
    out.copy_from_slice(bytemuck::cast_slice(&v));
    Ok(())
}
