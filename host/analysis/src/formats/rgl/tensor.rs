//! Mitsuba's tensor file (`mitsuba/core/tensor.h`, written by
//! `mitsuba.tensor_io.write`), which RGL `.bsdf` files are: the 12-byte
//! header `tensor_file\0`, version 1.0, a field count, then per field its
//! name, rank, type code, data offset and shape (little endian), and the
//! data of every field aligned to 8 bytes. Written here rather than through
//! a crate because no Rust crate reads or writes this format; [`read`] is
//! for the tests, to look at what was written.

use anyhow::{bail, ensure, Context, Result};

const MAGIC: &[u8; 12] = b"tensor_file\0";
/// Mitsuba 3's `Struct::Type` codes (`tensor_io.py`), also pbrt-v4's.
const UINT8: u8 = 1;
const FLOAT32: u8 = 10;
const ALIGN: usize = 8;

/// One field's values.
#[derive(Debug, Clone, PartialEq)]
pub enum Data {
    U8(Vec<u8>),
    F32(Vec<f32>),
}

/// A named tensor: its shape (outermost first) and its values in row-major order.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub name: String,
    pub shape: Vec<usize>,
    pub data: Data,
}

impl Field {
    pub fn f32(name: &str, shape: &[usize], data: Vec<f32>) -> Self {
        debug_assert_eq!(shape.iter().product::<usize>(), data.len(), "{name}");
        Field {
            name: name.into(),
            shape: shape.to_vec(),
            data: Data::F32(data),
        }
    }

    pub fn u8(name: &str, data: Vec<u8>) -> Self {
        Field {
            name: name.into(),
            shape: vec![data.len()],
            data: Data::U8(data),
        }
    }

    fn code(&self) -> u8 {
        match self.data {
            Data::U8(_) => UINT8,
            Data::F32(_) => FLOAT32,
        }
    }

    fn bytes(&self) -> Vec<u8> {
        match &self.data {
            Data::U8(v) => v.clone(),
            Data::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    }

    /// The values as `f32`, if that is the field's type.
    pub fn as_f32(&self) -> Option<&[f32]> {
        match &self.data {
            Data::F32(v) => Some(v),
            Data::U8(_) => None,
        }
    }
}

/// The file's bytes.
pub fn encode(fields: &[Field]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&(fields.len() as u32).to_le_bytes());
    let mut offset_at = Vec::with_capacity(fields.len());
    for f in fields {
        out.extend_from_slice(&(f.name.len() as u16).to_le_bytes());
        out.extend_from_slice(f.name.as_bytes());
        out.extend_from_slice(&(f.shape.len() as u16).to_le_bytes());
        out.push(f.code());
        offset_at.push(out.len());
        out.extend_from_slice(&0u64.to_le_bytes());
        for &n in &f.shape {
            out.extend_from_slice(&(n as u64).to_le_bytes());
        }
    }
    for (f, at) in fields.iter().zip(offset_at) {
        out.resize(out.len().div_ceil(ALIGN) * ALIGN, 0);
        let offset = out.len() as u64;
        out[at..at + 8].copy_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&f.bytes());
    }
    out
}

/// Reads a tensor file's fields (`u8` and `f32` ones; another type is an error).
pub fn read(bytes: &[u8]) -> Result<Vec<Field>> {
    ensure!(
        bytes.len() >= 18 && &bytes[..12] == MAGIC,
        "not a tensor file (no `tensor_file` header)"
    );
    ensure!(bytes[12..14] == [1, 0], "tensor file version {}.{}, not 1.0", bytes[12], bytes[13]);
    let mut at = 14;
    let mut take = |n: usize| -> Result<&[u8]> {
        let s = bytes.get(at..at + n).context("tensor file truncated in its header")?;
        at += n;
        Ok(s)
    };
    let le = |s: &[u8]| s.iter().rev().fold(0u64, |acc, &b| (acc << 8) | b as u64);
    let count = le(take(4)?);
    let mut fields = Vec::new();
    for _ in 0..count {
        let len = le(take(2)?) as usize;
        let name = String::from_utf8(take(len)?.to_vec()).context("field name is not UTF-8")?;
        let rank = le(take(2)?) as usize;
        let code = take(1)?[0];
        let offset = le(take(8)?) as usize;
        let shape = (0..rank).map(|_| take(8).map(|s| le(s) as usize)).collect::<Result<Vec<_>>>()?;
        let n: usize = shape.iter().product();
        let size = match code {
            UINT8 => 1,
            FLOAT32 => 4,
            other => bail!("field `{name}`: type code {other} (only uint8 and float32 are read)"),
        };
        let raw = bytes
            .get(offset..offset + n * size)
            .with_context(|| format!("field `{name}` runs past the end of the file"))?;
        let data = match code {
            UINT8 => Data::U8(raw.to_vec()),
            _ => Data::F32(raw.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()),
        };
        fields.push(Field { name, shape, data });
    }
    Ok(fields)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_read_back_as_written_at_aligned_offsets() {
        let fields = vec![
            Field::u8("description", b"abc".to_vec()),
            Field::f32("grid", &[2, 3], (0..6).map(|i| i as f32 * 0.5).collect()),
        ];
        let bytes = encode(&fields);
        assert_eq!(read(&bytes).unwrap(), fields);
        // The second field's data starts on an 8-byte boundary after the 3-byte one.
        let offset_of_grid = 12 + 2 + 4 + (2 + 11 + 2 + 1 + 8 + 8) + (2 + 4 + 2 + 1);
        let off = u64::from_le_bytes(bytes[offset_of_grid..offset_of_grid + 8].try_into().unwrap());
        assert_eq!(off % 8, 0);
        assert!(read(&bytes[..40]).is_err());
        assert!(read(b"not a tensor file at all").is_err());
    }
}
