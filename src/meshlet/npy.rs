//! numpy's `.npy` arrays of integers, through the `npyz` crate: what the label files and the
//! `.npz` meshlet files hold. Any integer dtype and byte order reads; the header's element count
//! is checked against a caller's bound and against the bytes present before anything is
//! allocated, so a lying header is an error, not a huge allocation.

use npyz::{DType, NpyFile, NpyHeader, Order, TypeChar, WriterBuilder};

/// An integer array as read: its shape and its values in C order, widened to `u64`.
pub(crate) struct IntArray {
    /// The shape as written.
    pub shape: Vec<u64>,
    /// The values, row-major whatever the file's order.
    pub values: Vec<u64>,
}

/// Reads an integer `.npy` array of at most `max_len` elements; a negative value is an error
/// naming its place.
pub(crate) fn read_integers(bytes: &[u8], max_len: u64) -> Result<IntArray, String> {
    check_shape(bytes, max_len)?;
    let mut data = bytes;
    let header = NpyHeader::from_reader(&mut data).map_err(|e| format!("not a .npy array: {e}"))?;
    let shape = header.shape().to_vec();
    let len = shape
        .iter()
        .try_fold(1u64, |n, &d| n.checked_mul(d))
        .filter(|&n| n <= max_len)
        .ok_or_else(|| format!("array of shape {shape:?} is larger than {max_len} elements"))?;
    let DType::Plain(ts) = header.dtype() else {
        return Err(format!("holds {}, not integers", header.dtype().descr()));
    };
    let size = ts.size_field();
    if !matches!(ts.type_char(), TypeChar::Int | TypeChar::Uint) || ![1, 2, 4, 8].contains(&size) {
        return Err(format!("holds {ts}, not integers"));
    }
    if len.saturating_mul(size) > data.len() as u64 {
        return Err(format!(
            "header announces {len} elements of {size} bytes, but {} bytes follow",
            data.len()
        ));
    }
    let order = header.order();
    let file = NpyFile::with_header(header, data);
    let io = |e: std::io::Error| format!("cannot read the array: {e}");
    let values: Vec<i128> = match (ts.type_char(), size) {
        (TypeChar::Int, 1) => widen(file.into_vec::<i8>().map_err(io)?),
        (TypeChar::Int, 2) => widen(file.into_vec::<i16>().map_err(io)?),
        (TypeChar::Int, 4) => widen(file.into_vec::<i32>().map_err(io)?),
        (TypeChar::Int, _) => widen(file.into_vec::<i64>().map_err(io)?),
        (_, 1) => widen(file.into_vec::<u8>().map_err(io)?),
        (_, 2) => widen(file.into_vec::<u16>().map_err(io)?),
        (_, 4) => widen(file.into_vec::<u32>().map_err(io)?),
        (_, _) => widen(file.into_vec::<u64>().map_err(io)?),
    };
    if let Some(i) = values.iter().position(|&v| v < 0) {
        return Err(format!("element {i} is negative ({})", values[i]));
    }
    let mut values: Vec<u64> = values.into_iter().map(|v| v as u64).collect();
    if order == Order::Fortran && shape.len() == 2 {
        values = transpose(&values, shape[0] as usize, shape[1] as usize);
    }
    Ok(IntArray { shape, values })
}

/// The header's length and shape, checked before `npyz` reads them: it allocates the announced
/// header length up front, and its element count is a product that overflows `u64` for a shape
/// such as `(2**32, 2**32)`; both must be errors, not an allocation or a panic. A header this
/// cannot make out is left to `npyz` to refuse.
fn check_shape(bytes: &[u8], max_len: u64) -> Result<(), String> {
    let (len, start): (Option<usize>, usize) = match bytes.get(6) {
        Some(1) => (
            bytes
                .get(8..10)
                .map(|b| u16::from_le_bytes([b[0], b[1]]) as usize),
            10,
        ),
        Some(2 | 3) => (
            bytes
                .get(8..12)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize),
            12,
        ),
        _ => (None, 0),
    };
    let Some(len) = len else {
        return Ok(());
    };
    // `npyz` allocates the header's announced length before reading it.
    let Some(header) = bytes.get(start..start + len) else {
        return Err(format!(
            "header of {len} bytes runs past the end of the file"
        ));
    };
    let header = String::from_utf8_lossy(header);
    let Some(tuple) = header
        .split_once("'shape'")
        .and_then(|(_, rest)| rest.split_once('('))
        .and_then(|(_, rest)| rest.split_once(')'))
        .map(|(inside, _)| inside)
    else {
        return Ok(());
    };
    let mut n = 1u64;
    for d in tuple.split(',').map(str::trim).filter(|d| !d.is_empty()) {
        let Ok(d) = d.parse::<u64>() else {
            return Ok(());
        };
        n = n
            .checked_mul(d)
            .filter(|&n| n <= max_len)
            .ok_or_else(|| format!("array of shape ({tuple}) is larger than {max_len} elements"))?;
    }
    Ok(())
}

fn widen<T: Into<i128>>(v: Vec<T>) -> Vec<i128> {
    v.into_iter().map(Into::into).collect()
}

/// Column-major `rows x cols` to row-major.
fn transpose(v: &[u64], rows: usize, cols: usize) -> Vec<u64> {
    let mut out = vec![0; v.len()];
    for r in 0..rows {
        for c in 0..cols {
            out[r * cols + c] = v[c * rows + r];
        }
    }
    out
}

/// A `.npy` array of `shape` holding `values` (row-major) in their own little-endian dtype.
pub(crate) fn write<T: npyz::AutoSerialize>(shape: &[u64], values: &[T]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut out)
        .begin_nd()
        .expect("writing to memory cannot fail");
    w.extend(values).expect("writing to memory cannot fail");
    w.finish().expect("writing to memory cannot fail");
    out
}
