//! The mutations. Each takes a seed and a random stream and returns the mutated file; all are
//! deterministic in the stream.

use super::corpus::{Field, Seed};
use super::Mutation;
use serde_json::Value;

/// A small deterministic random stream (splitmix64).
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = crate::mesh::generate::splitmix64(self.0);
        self.0
    }
    /// Uniform in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 > 1.0 - p
    }
    /// A random element.
    pub fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

/// Integers that break readers: zero, one, signed and unsigned 32-bit edges, negative, huge.
const NUMBERS: &[i128] = &[
    0,
    1,
    2,
    255,
    65535,
    65536,
    1 << 31,
    (1 << 32) - 1,
    1 << 32,
    -1,
    -(1 << 31),
    1 << 62,
    (1 << 64) - 1,
    100_000_000_000_000_000_000,
];

/// Float texts and bit patterns: NaN, infinities, denormals, negative zero, beyond f32.
const FLOAT_TEXT: &[&str] = &[
    "nan", "NaN", "inf", "-inf", "1e-45", "1e-40", "-0", "3.4e38", "1e39", "-1e39", "1e-320",
];
const FLOAT_BITS: &[u32] = &[
    0x7fc0_0000,
    0x7f80_0000,
    0xff80_0000,
    0x0000_0001,
    0x007f_ffff,
    0x8000_0000,
    0x7f7f_ffff,
    0xffff_ffff,
];

/// Applies `m` to `seed`. Mutations that do not apply to the seed's format fall back to a byte flip
/// (the caller only picks applicable ones, see [`Mutation::applies`]).
pub fn apply(m: Mutation, seed: &Seed, rng: &mut Rng) -> Vec<u8> {
    let b = &seed.bytes;
    match m {
        Mutation::Flip => flip(b.clone(), rng),
        Mutation::Truncate => truncate(b, &seed.boundaries, rng),
        Mutation::HeaderNumber => header_number(b, &seed.numbers, rng),
        Mutation::Duplicate => duplicate(b.clone(), rng),
        Mutation::FloatSpecial => float_special(seed, rng),
        Mutation::TokenDelete | Mutation::TokenRepeat => {
            tokens(seed, m == Mutation::TokenRepeat, rng)
        }
        Mutation::JsonIndex | Mutation::JsonType | Mutation::JsonCycle => json(seed, m, rng),
        Mutation::ZeroRange => zero_range(b.clone(), rng),
        Mutation::Stacked => {
            let mut out = b.clone();
            for _ in 0..2 + rng.below(3) {
                out = match rng.below(4) {
                    0 => flip(out, rng),
                    1 => duplicate(out, rng),
                    2 => zero_range(out, rng),
                    _ => truncate(&out, &[], rng),
                };
            }
            out
        }
    }
}

/// Flips 1 to 8 random bits.
pub fn flip(mut b: Vec<u8>, rng: &mut Rng) -> Vec<u8> {
    if b.is_empty() {
        return b;
    }
    for _ in 0..1 + rng.below(8) {
        let i = rng.below(b.len());
        b[i] ^= 1 << rng.below(8);
    }
    b
}

/// Cuts at a structural boundary (or one byte either side of it); a random offset 1 time in 8.
pub fn truncate(b: &[u8], boundaries: &[usize], rng: &mut Rng) -> Vec<u8> {
    let at = if boundaries.is_empty() || rng.chance(0.125) {
        rng.below(b.len() + 1)
    } else {
        let k = *rng.pick(boundaries) as i64 + rng.below(3) as i64 - 1;
        k.clamp(0, b.len() as i64) as usize
    };
    b[..at.min(b.len())].to_vec()
}

/// Replaces a header number or count with a value from `NUMBERS`.
pub fn header_number(b: &[u8], fields: &[Field], rng: &mut Rng) -> Vec<u8> {
    if fields.is_empty() {
        return flip(b.to_vec(), rng);
    }
    let v = *rng.pick(NUMBERS);
    match *rng.pick(fields) {
        Field::Text { start, end } => splice(b, start, end, v.to_string().as_bytes()),
        Field::Bin { at, width, be } => {
            let mut out = b.to_vec();
            let mut bytes = (v as u128).to_le_bytes()[..width as usize].to_vec();
            if be {
                bytes.reverse();
            }
            if at + width as usize <= out.len() {
                out[at..at + width as usize].copy_from_slice(&bytes);
            }
            out
        }
    }
}

/// Copies a chunk (1 byte to half the file) and inserts it right after itself or anywhere.
pub fn duplicate(mut b: Vec<u8>, rng: &mut Rng) -> Vec<u8> {
    if b.is_empty() {
        return b;
    }
    let a = rng.below(b.len());
    let len = 1 + rng.below((b.len() - a).min(b.len() / 2 + 1));
    let chunk = b[a..a + len].to_vec();
    let at = if rng.chance(0.5) {
        a + len
    } else {
        rng.below(b.len() + 1)
    };
    b.splice(at..at, chunk);
    b
}

/// Zeroes a range: short (up to 64 bytes) mostly, up to a quarter of the file sometimes.
pub fn zero_range(mut b: Vec<u8>, rng: &mut Rng) -> Vec<u8> {
    if b.is_empty() {
        return b;
    }
    let a = rng.below(b.len());
    let max = if rng.chance(0.25) {
        b.len() / 4 + 1
    } else {
        64
    };
    let len = 1 + rng.below((b.len() - a).min(max));
    b[a..a + len].fill(0);
    b
}

/// Writes NaN, an infinity, a denormal or an out-of-range value into 1 to 3 float fields.
fn float_special(seed: &Seed, rng: &mut Rng) -> Vec<u8> {
    // Seeds whose buffer holds no plain floats (quantised, compressed) fall through to bit flips.
    if let Some(g) = seed.gltf.as_ref().filter(|g| !g.floats.is_empty()) {
        let mut bin = g.bin.clone();
        for _ in 0..1 + rng.below(3) {
            let at = *rng.pick(&g.floats);
            bin[at..at + 4].copy_from_slice(&rng.pick(FLOAT_BITS).to_le_bytes());
        }
        return g.assemble(&g.json, &bin);
    }
    if seed.floats.is_empty() {
        return flip(seed.bytes.clone(), rng);
    }
    // Text splices change lengths, so apply them from the back.
    let mut picks: Vec<Field> = (0..1 + rng.below(3))
        .map(|_| *rng.pick(&seed.floats))
        .collect();
    picks.sort_by_key(|f| match f {
        Field::Text { start, .. } => std::cmp::Reverse(*start),
        Field::Bin { at, .. } => std::cmp::Reverse(*at),
    });
    picks.dedup_by_key(|f| match f {
        Field::Text { start, .. } => *start,
        Field::Bin { at, .. } => *at,
    });
    let mut out = seed.bytes.clone();
    for f in picks {
        match f {
            Field::Text { start, end } => {
                out = splice(&out, start, end, rng.pick(FLOAT_TEXT).as_bytes())
            }
            Field::Bin { at, width, be } => {
                let bits = *rng.pick(FLOAT_BITS);
                let mut bytes = if width == 8 {
                    (f32::from_bits(bits) as f64).to_le_bytes().to_vec()
                } else {
                    bits.to_le_bytes().to_vec()
                };
                if be {
                    bytes.reverse();
                }
                out[at..at + width as usize].copy_from_slice(&bytes);
            }
        }
    }
    out
}

/// Whitespace-separated token spans of `text`.
fn token_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = None;
    for (i, c) in text.iter().enumerate() {
        match (c.is_ascii_whitespace(), start) {
            (false, None) => start = Some(i),
            (true, Some(s)) => {
                spans.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        spans.push((s, text.len()));
    }
    spans
}

/// Deletes or repeats one token (1 to 3 in a row) of the text part; GLB's JSON chunk is edited as
/// text and re-wrapped with correct chunk lengths, so the edit reaches the JSON parser.
fn tokens(seed: &Seed, repeat: bool, rng: &mut Rng) -> Vec<u8> {
    let edit = |text: &[u8], rng: &mut Rng| -> Vec<u8> {
        let spans = token_spans(text);
        if spans.is_empty() {
            return text.to_vec();
        }
        let k = rng.below(spans.len());
        let n = (1 + rng.below(3)).min(spans.len() - k);
        let (s, e) = (spans[k].0, spans[k + n - 1].1);
        if repeat {
            let mut copy = text[s..e].to_vec();
            copy.push(b' ');
            splice(text, s, s, &copy)
        } else {
            splice(text, s, e, b"")
        }
    };
    if let Some(g) = seed.gltf.as_ref().filter(|g| g.glb) {
        let text = g.json_text(&g.json, &g.bin);
        return g.assemble_text(&edit(&text, rng), &g.bin);
    }
    let mut out = edit(&seed.bytes[..seed.text_end], rng);
    out.extend_from_slice(&seed.bytes[seed.text_end..]);
    out
}

/// Every path to a value in a JSON document, as (parent pointer, key or index).
fn paths(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(o) => o.iter().for_each(|(k, x)| {
            let p = format!("{at}/{k}");
            out.push(p.clone());
            paths(x, p, out);
        }),
        Value::Array(a) => a.iter().enumerate().for_each(|(i, x)| {
            let p = format!("{at}/{i}");
            out.push(p.clone());
            paths(x, p, out);
        }),
        _ => {}
    }
}

/// JSON-aware edits of a glTF: out-of-range integers, wrong types, node cycles and shared children.
fn json(seed: &Seed, m: Mutation, rng: &mut Rng) -> Vec<u8> {
    let Some(g) = &seed.gltf else {
        return flip(seed.bytes.clone(), rng);
    };
    let mut doc = g.json.clone();
    let mut all = Vec::new();
    paths(&doc, String::new(), &mut all);
    match m {
        Mutation::JsonIndex => {
            let ints: Vec<&String> = all
                .iter()
                .filter(|p| doc.pointer(p).is_some_and(|v| v.is_u64()))
                .collect();
            let p = (*rng.pick(&ints)).clone();
            let cur = doc.pointer(&p).and_then(Value::as_u64).unwrap_or(0);
            let v: Value = match rng.below(6) {
                0 => (cur + 1).into(),
                1 => (cur + 3).into(),
                2 => (-1).into(),
                3 => (1u64 << 32).into(),
                4 => (u64::MAX).into(),
                _ => 2_147_483_647.into(),
            };
            *doc.pointer_mut(&p).expect("path exists") = v;
        }
        Mutation::JsonType => {
            let p = rng.pick(&all).clone();
            let v = match rng.below(7) {
                0 => Value::String("x".into()),
                1 => Value::Array(vec![]),
                2 => serde_json::json!({}),
                3 => Value::Null,
                4 => Value::Bool(true),
                5 => serde_json::json!(1.5),
                _ => serde_json::json!([1, 2]),
            };
            *doc.pointer_mut(&p).expect("path exists") = v;
        }
        _ => cycle(&mut doc, rng),
    }
    g.assemble(&doc, &g.bin)
}

/// Breaks the node tree: a self-loop, a two-cycle, a shared child, a child listed as a scene root,
/// a 40-level diamond (2^40 paths if followed naively), or a 3,000-deep chain.
fn cycle(doc: &mut Value, rng: &mut Rng) {
    let nodes = doc["nodes"].as_array().map_or(0, |a| a.len());
    let push_child = |doc: &mut Value, parent: usize, child: usize| {
        let n = &mut doc["nodes"][parent];
        if !n["children"].is_array() {
            n["children"] = Value::Array(vec![]);
        }
        n["children"]
            .as_array_mut()
            .expect("made an array")
            .push(child.into());
    };
    match rng.below(6) {
        0 => {
            let i = rng.below(nodes);
            push_child(doc, i, i);
        }
        1 => push_child(doc, 1, 0),
        2 => push_child(doc, 1, 2),
        3 => {
            if let Some(r) = doc["scenes"][0]["nodes"].as_array_mut() {
                r.push(1.into());
            }
        }
        4 => {
            let base = nodes;
            let arr = doc["nodes"].as_array_mut().expect("seed has nodes");
            for k in 0..40 {
                let next = base + k + 1;
                arr.push(serde_json::json!({"children": [next, next]}));
            }
            arr.push(serde_json::json!({"mesh": 0}));
            push_child(doc, 0, base);
        }
        _ => {
            let base = nodes;
            let arr = doc["nodes"].as_array_mut().expect("seed has nodes");
            for k in 0..3000 {
                arr.push(serde_json::json!({"children": [base + k + 1], "translation": [0.0, 0.0, 1e-3]}));
            }
            arr.push(serde_json::json!({"mesh": 1}));
            push_child(doc, 0, base);
        }
    }
}

/// `b` with `start..end` replaced by `with`.
fn splice(b: &[u8], start: usize, end: usize, with: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(b.len() + with.len());
    out.extend_from_slice(&b[..start.min(b.len())]);
    out.extend_from_slice(with);
    out.extend_from_slice(&b[end.min(b.len())..]);
    out
}
