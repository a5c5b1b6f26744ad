//! The one bit stream every codec in this module writes and reads: values packed least
//! significant bit first, bit `k` of the stream being bit `k % 8` of byte `k / 8`. That is the
//! order the shaders' `bits_at` (glsl/compressed.glsl) reads the same bytes in as little-endian
//! 32-bit words, so the encoders, the CPU decoders and the GPU decoders agree by construction.
//!
//! A field is at most 32 bits wide; a width of 0 writes nothing and reads 0. Readers report a
//! read past the end instead of panicking, since decoders take untrusted buffers.

use super::DecodeError;

/// Appends values to a bit stream, least significant bit first.
#[derive(Debug, Default)]
pub(crate) struct BitWriter {
    out: Vec<u8>,
    at: usize,
}

impl BitWriter {
    /// An empty stream.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// Bits written so far (the next write's offset).
    pub(crate) fn at(&self) -> usize {
        self.at
    }

    /// Writes the low `bits` (<= 32) bits of `v`; higher bits of `v` are ignored. The bytes
    /// always cover every bit written (a partial last byte is zero above the stream's end).
    pub(crate) fn put(&mut self, bits: u32, v: u32) {
        debug_assert!(bits <= 32, "{bits} bits");
        let end = self.at + bits as usize;
        self.out.resize(self.out.len().max(end.div_ceil(8)), 0);
        for k in 0..bits as usize {
            if v >> k & 1 == 1 {
                self.out[(self.at + k) / 8] |= 1 << ((self.at + k) % 8);
            }
        }
        self.at = end;
    }

    /// Zero-pads to a multiple of `unit` bits (8: a byte, 32: a word), the bytes included;
    /// returns the padding bits.
    pub(crate) fn pad(&mut self, unit: usize) -> usize {
        let to = self.at.div_ceil(unit) * unit;
        let p = to - self.at;
        self.at = to;
        self.out.resize(to / 8, 0);
        p
    }

    /// The bytes written.
    pub(crate) fn bytes(&self) -> &[u8] {
        &self.out
    }

    /// The bytes written, taken.
    pub(crate) fn into_bytes(self) -> Vec<u8> {
        self.out
    }
}

/// Reads `bits` (<= 32) bits at bit offset `at` of `data`, or `None` past the end.
fn read_bits(data: &[u8], at: usize, bits: u32) -> Option<u32> {
    if bits == 0 {
        return Some(0);
    }
    let end = at.checked_add(bits as usize)?;
    if end > data.len() * 8 {
        return None;
    }
    let mut v = 0u64;
    let first = at / 8;
    let last = (end - 1) / 8;
    for (k, &b) in data[first..=last].iter().enumerate() {
        v |= (b as u64) << (8 * k);
    }
    Some(((v >> (at % 8)) & ((1u64 << bits) - 1)) as u32)
}

/// Reads a bit stream from a bit offset on; a read past the end is a
/// [`DecodeError::Truncated`] naming the meshlet and the part being read.
#[derive(Clone, Debug)]
pub(crate) struct BitReader<'a> {
    data: &'a [u8],
    at: usize,
    meshlet: usize,
    what: &'static str,
}

impl<'a> BitReader<'a> {
    /// A reader of `data` from bit `at`, for meshlet `meshlet`'s `what` (named in errors).
    pub(crate) fn new(data: &'a [u8], at: usize, meshlet: usize, what: &'static str) -> Self {
        Self {
            data,
            at,
            meshlet,
            what,
        }
    }

    /// Bit offset of the next read.
    pub(crate) fn at(&self) -> usize {
        self.at
    }

    /// Skips to the next multiple of `unit` bits (8: a byte, 32: a word).
    pub(crate) fn align(&mut self, unit: usize) {
        self.at = self.at.div_ceil(unit) * unit;
    }

    /// Reads `bits` (<= 32) bits; past the end, an error and the position unchanged.
    pub(crate) fn get(&mut self, bits: u32) -> Result<u32, DecodeError> {
        let v = read_bits(self.data, self.at, bits).ok_or(DecodeError::Truncated {
            meshlet: self.meshlet,
            what: self.what,
        })?;
        self.at += bits as usize;
        Ok(v)
    }
}

/// Bits of a non-negative value (0 for 0).
pub(crate) fn width(v: u64) -> u32 {
    64 - v.leading_zeros()
}

/// Bits that hold the values `0..n`.
pub(crate) fn bits_for(n: usize) -> u32 {
    if n <= 1 {
        0
    } else {
        usize::BITS - (n - 1).leading_zeros()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reader(d: &[u8]) -> BitReader<'_> {
        BitReader::new(d, 0, 7, "test")
    }

    #[test]
    fn values_round_trip() {
        let vals = [
            (3u32, 5u32),
            (0, 0),
            (17, 99_999),
            (1, 1),
            (32, u32::MAX),
            (9, 300),
        ];
        let mut w = BitWriter::new();
        for &(b, v) in &vals {
            w.put(b, v);
        }
        assert_eq!(w.at(), 62);
        assert_eq!(w.bytes().len(), 8);
        let d = w.into_bytes();
        let mut r = reader(&d);
        for &(b, v) in &vals {
            assert_eq!(r.get(b), Ok(v));
        }
        assert_eq!(r.at(), 62);
    }

    #[test]
    fn every_width_round_trips_at_every_alignment() {
        for shift in 0..8 {
            for bits in 0..=32u32 {
                let top = if bits == 32 {
                    u32::MAX
                } else {
                    (1u32 << bits).wrapping_sub(1)
                };
                let vals = [0, top, top / 3, top & 0x5555_5555];
                let mut w = BitWriter::new();
                w.put(shift, 0b1011_0110);
                for v in vals {
                    w.put(bits, v);
                }
                let d = w.into_bytes();
                assert_eq!(d.len(), (shift as usize + 4 * bits as usize).div_ceil(8));
                let mut r = reader(&d);
                assert_eq!(r.get(shift), Ok(0b1011_0110 & ((1 << shift) - 1)));
                for v in vals {
                    assert_eq!(r.get(bits), Ok(v), "{bits} bits after {shift}");
                }
            }
        }
    }

    #[test]
    fn least_significant_bit_first() {
        let mut w = BitWriter::new();
        w.put(4, 0xA);
        w.put(8, 0xFF);
        w.put(3, 0b101);
        // Higher bits of a value are not written.
        w.put(1, 0b10);
        assert_eq!(w.bytes(), &[0xFA, 0x5F]);
    }

    #[test]
    fn padding_fills_with_zeros() {
        let mut w = BitWriter::new();
        w.put(5, 31);
        assert_eq!(w.pad(8), 3);
        assert_eq!(w.pad(8), 0);
        w.put(1, 1);
        assert_eq!(w.pad(32), 23);
        assert_eq!(w.bytes(), &[31, 1, 0, 0]);
        let mut r = reader(w.bytes());
        r.get(1).unwrap();
        r.align(8);
        assert_eq!(r.at(), 8);
        r.align(32);
        assert_eq!(r.at(), 32);
    }

    #[test]
    fn reads_past_the_end_are_errors() {
        let d = [0xFFu8, 0x01];
        let mut r = reader(&d);
        assert_eq!(r.get(9), Ok(0x1FF));
        let trunc = Err(DecodeError::Truncated {
            meshlet: 7,
            what: "test",
        });
        assert_eq!(r.get(8), trunc);
        // The failed read did not move the reader; what remains can still be read.
        assert_eq!(r.get(7), Ok(0));
        assert_eq!(r.get(1), trunc);
        assert_eq!(r.get(0), Ok(0));
        assert!(BitReader::new(&d, usize::MAX, 0, "test").get(1).is_err());
        assert!(reader(&[]).get(32).is_err());
    }

    #[test]
    fn widths() {
        assert_eq!([0, 1, 2, 3, 255, 256].map(width), [0, 1, 2, 2, 8, 9]);
        assert_eq!(
            [0, 1, 2, 3, 4, 5, 256, 257].map(bits_for),
            [0, 0, 1, 2, 2, 3, 8, 9]
        );
    }
}
