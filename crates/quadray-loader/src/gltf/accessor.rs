//! Accessor checks made before the gltf crate's readers touch the data.
//!
//! The gltf crate validates indices between JSON objects, but not that an accessor's elements lie
//! inside its buffer view, that the view lies inside its buffer, that the element type is the one
//! the reader assumes, or that counts are sane; its reader panics (debug assertions, integer
//! overflow) or silently truncates on such files. Every accessor quadray reads passes through
//! [`check`] first, with checked arithmetic throughout.

use gltf::accessor::{DataType, Dimensions};
use gltf::buffer::View;

/// Most elements one accessor may hold (2²⁸ ≈ 268 million; a POSITION accessor that large is
/// 3 GiB of floats).
pub const MAX_ELEMENTS: usize = 1 << 28;

/// Most bytes an accessor without a buffer view may decode to (256 MiB). Such an accessor is all
/// zeros but for its sparse values, so its size is not backed by bytes of the file: without this
/// bound a 1 kB file could ask for 2²⁸ VEC3 elements, 3 GiB.
pub const MAX_UNBACKED_BYTES: usize = 256 << 20;

/// What an accessor must look like to be read for some purpose.
pub struct Expect<'a> {
    /// Allowed shapes (SCALAR, VEC2, …).
    pub dimensions: &'a [Dimensions],
    /// Allowed component types.
    pub types: &'a [DataType],
}

fn type_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

fn dims_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

/// Checks that `accessor` can be read safely as `expect` from `buffers`; the error says which
/// accessor and what is wrong.
pub fn check(
    accessor: &gltf::Accessor<'_>,
    expect: &Expect<'_>,
    buffers: &[Vec<u8>],
) -> Result<(), String> {
    let name = format!("accessor {}", accessor.index());
    let count = accessor.count();
    if count == 0 || count > MAX_ELEMENTS {
        return Err(format!(
            "{name} has {count} elements (expected 1..={MAX_ELEMENTS})"
        ));
    }
    if !expect.dimensions.contains(&accessor.dimensions())
        || !expect.types.contains(&accessor.data_type())
    {
        let allowed = |d: &[&str]| d.join("/");
        return Err(format!(
            "{name} is {} of {}, expected {} of {}",
            dims_name(accessor.dimensions()),
            type_name(accessor.data_type()),
            allowed(
                &expect
                    .dimensions
                    .iter()
                    .map(|&d| dims_name(d))
                    .collect::<Vec<_>>()
            ),
            allowed(
                &expect
                    .types
                    .iter()
                    .map(|&t| type_name(t))
                    .collect::<Vec<_>>()
            ),
        ));
    }
    let element = accessor.size();
    match accessor.view() {
        Some(view) => check_range(&name, &view, accessor.offset(), count, element, buffers)?,
        None => {
            // Decoded as 4-byte floats or integers, whatever the component type.
            let decoded = count.saturating_mul(accessor.dimensions().multiplicity() * 4);
            if decoded > MAX_UNBACKED_BYTES {
                return Err(format!(
                    "{name} has no buffer view, and its {count} elements would take {} MiB \
                     decoded (at most {} MiB for an accessor whose data is not in the file)",
                    decoded >> 20,
                    MAX_UNBACKED_BYTES >> 20
                ));
            }
        }
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return Err(format!("{name}: sparse count {n} must be in 1..={count}"));
        }
        let indices = sparse.indices();
        let index_size = indices.index_type().size();
        check_range(
            &format!("{name} sparse indices"),
            &indices.view(),
            indices.offset(),
            n,
            index_size,
            buffers,
        )?;
        let values = sparse.values();
        check_range(
            &format!("{name} sparse values"),
            &values.view(),
            values.offset(),
            n,
            element,
            buffers,
        )?;
        // Sparse indices must name existing elements (the spec also wants them increasing).
        let view = indices.view();
        let data = &buffers[view.buffer().index()][view.offset() + indices.offset()..];
        let stride = view.stride().unwrap_or(index_size);
        let mut previous = None;
        for k in 0..n {
            let at = &data[k * stride..];
            let i = match index_size {
                1 => at[0] as usize,
                2 => u16::from_le_bytes([at[0], at[1]]) as usize,
                _ => u32::from_le_bytes([at[0], at[1], at[2], at[3]]) as usize,
            };
            if i >= count || previous.is_some_and(|p| i <= p) {
                return Err(format!(
                    "{name}: sparse index {i} is out of range or not increasing ({count} elements)"
                ));
            }
            previous = Some(i);
        }
    }
    Ok(())
}

/// Checks that `count` elements of `element` bytes at `offset` in `view` (with its stride) lie in
/// the view, and the view in its buffer.
fn check_range(
    name: &str,
    view: &View<'_>,
    offset: usize,
    count: usize,
    element: usize,
    buffers: &[Vec<u8>],
) -> Result<(), String> {
    let stride = view.stride().unwrap_or(element);
    if stride < element {
        return Err(format!(
            "{name}: byteStride {stride} is smaller than one element ({element} bytes)"
        ));
    }
    let needed = stride
        .checked_mul(count - 1)
        .and_then(|b| b.checked_add(element))
        .and_then(|b| b.checked_add(offset));
    let view_end = view.offset().checked_add(view.length());
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    match (needed, view_end) {
        (Some(needed), Some(view_end)) if needed <= view.length() && view_end <= buffer_len => {
            Ok(())
        }
        (Some(needed), Some(view_end)) if needed <= view.length() => Err(format!(
            "{name}: buffer view {} ends at byte {view_end}, past the end of buffer {} ({buffer_len} bytes)",
            view.index(),
            view.buffer().index()
        )),
        _ => Err(format!(
            "{name}: {count} elements of {element} bytes (stride {stride}) from byte {offset} run past the end of buffer view {} ({} bytes)",
            view.index(),
            view.length()
        )),
    }
}
