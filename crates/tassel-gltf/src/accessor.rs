//! Checks an accessor before the `gltf` crate's reader sees it.
//!
//! The reader trusts the file: a view stride smaller than the element, an element type it
//! does not expect (an index accessor of BYTE or FLOAT, a VEC2 read as positions) or a
//! count of zero make it assert, hit `unreachable!` or read past its slice. Every accessor
//! the importer reads goes through [`check`] first, so that such a file is an error that
//! names the accessor, never a panic.

use gltf::accessor::{DataType, Dimensions};

/// The most elements one accessor may hold (16 M: 192 MiB of `VEC3` floats).
pub(crate) const MAX_ELEMENTS: usize = 1 << 24;

/// Checks that `accessor` (read as `what`) has one of the `allowed` element types, at least
/// one element and no more than [`MAX_ELEMENTS`], and that every element it names lies
/// inside its buffer view and the view's buffer (`buffer_len`: bytes per buffer index),
/// sparse parts included.
pub(crate) fn check(
    accessor: &gltf::Accessor,
    allowed: &[(DataType, Dimensions)],
    buffer_len: &dyn Fn(usize) -> usize,
    what: &str,
) -> Result<(), String> {
    let index = accessor.index();
    let bad = |m: String| Err(format!("{what}: accessor {index} {m}"));
    let kind = (accessor.data_type(), accessor.dimensions());
    if !allowed.contains(&kind) {
        let names: Vec<String> = allowed
            .iter()
            .map(|(t, d)| format!("{d:?} {t:?}"))
            .collect();
        return bad(format!(
            "holds {:?} {:?}; expected {}",
            kind.1,
            kind.0,
            names.join(" or ")
        ));
    }
    let count = accessor.count();
    if count == 0 {
        return bad("has no elements".into());
    }
    if count > MAX_ELEMENTS {
        return bad(format!(
            "has {count} elements, more than the limit of {MAX_ELEMENTS}"
        ));
    }
    let element = accessor.size();
    if let Some(view) = accessor.view() {
        check_range(
            &view,
            accessor.offset(),
            count,
            element,
            buffer_len,
            &format!("{what}: accessor {index}"),
        )?;
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return bad(format!(
                "has {n} sparse elements for {count} elements (1..={count})"
            ));
        }
        let indices = sparse.indices();
        check_range(
            &indices.view(),
            indices.offset(),
            n,
            indices.index_type().size(),
            buffer_len,
            &format!("{what}: accessor {index} sparse indices"),
        )?;
        let values = sparse.values();
        check_range(
            &values.view(),
            values.offset(),
            n,
            element,
            buffer_len,
            &format!("{what}: accessor {index} sparse values"),
        )?;
    } else if accessor.view().is_none() {
        return bad("has neither a bufferView nor sparse values".into());
    }
    Ok(())
}

/// `count` elements of `element` bytes from `offset` in `view` fit the view and its
/// buffer, with a stride of at least one element.
fn check_range(
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    element: usize,
    buffer_len: &dyn Fn(usize) -> usize,
    what: &str,
) -> Result<(), String> {
    let stride = view.stride().unwrap_or(element);
    if stride < element {
        return Err(format!(
            "{what}: bufferView {} has a byteStride of {stride}, smaller than its {element}-byte element",
            view.index()
        ));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|s| s.checked_add(offset))
        .and_then(|s| s.checked_add(element));
    let view_end = view.offset().checked_add(view.length());
    match (end, view_end) {
        (Some(end), Some(view_end))
            if end <= view.length() && view_end <= buffer_len(view.buffer().index()) =>
        {
            Ok(())
        }
        _ => Err(format!(
            "{what}: {count} elements of {element} bytes (stride {stride}) from byte {offset} \
             run past the end of bufferView {} ({} bytes) or its buffer",
            view.index(),
            view.length()
        )),
    }
}
