//! C arguments as Rust values: arrays as slices (null only for an empty
//! array), strings as text, the resource location's `file:` URI as a path.

use std::ffi::{CStr, c_char};
use std::path::PathBuf;

use super::instance::CallError;

/// A slice from a C array; null is allowed only for an empty array.
///
/// # Safety
/// A non-null `pointer` points to `n` valid elements.
pub(crate) unsafe fn input_slice<'a, T>(
    pointer: *const T,
    n: usize,
    what: &str,
) -> Result<&'a [T], CallError> {
    if n == 0 {
        return Ok(&[]);
    }
    if pointer.is_null() {
        return Err(CallError::InvalidArgument(format!(
            "{what} is a null pointer for {n} values"
        )));
    }
    // SAFETY: non-null and, by the caller's guarantee, n elements long.
    Ok(unsafe { std::slice::from_raw_parts(pointer, n) })
}

/// A mutable slice from a C array; null is allowed only for an empty array.
///
/// # Safety
/// A non-null `pointer` points to `n` valid, writable elements.
pub(crate) unsafe fn output_slice<'a, T>(
    pointer: *mut T,
    n: usize,
    what: &str,
) -> Result<&'a mut [T], CallError> {
    if n == 0 {
        return Ok(&mut []);
    }
    if pointer.is_null() {
        return Err(CallError::InvalidArgument(format!(
            "{what} is a null pointer for {n} values"
        )));
    }
    // SAFETY: non-null and, by the caller's guarantee, n elements long.
    Ok(unsafe { std::slice::from_raw_parts_mut(pointer, n) })
}

/// A NUL-terminated C string as text (lossy), or `None` for null.
pub(crate) fn text(pointer: *const c_char) -> Option<String> {
    if pointer.is_null() {
        return None;
    }
    // SAFETY: a non-null string argument is NUL-terminated by both standards.
    Some(
        unsafe { CStr::from_ptr(pointer) }
            .to_string_lossy()
            .into_owned(),
    )
}

/// The folder a `file:` URI names (FMPy passes `file:///...`).
pub(crate) fn resource_folder(uri: &str) -> Result<PathBuf, String> {
    if let Some(authority) = uri.strip_prefix("file://")
        && !authority.starts_with('/')
        && !authority.starts_with("localhost/")
    {
        return Err(format!(
            "resourceLocation \"{uri}\" names a remote host; only local file: URIs are supported"
        ));
    }
    let rest = uri
        .strip_prefix("file://localhost/")
        .map(|r| format!("/{r}"))
        .or_else(|| uri.strip_prefix("file:///").map(|r| format!("/{r}")))
        .or_else(|| uri.strip_prefix("file:/").map(|r| format!("/{r}")))
        .ok_or_else(|| format!("resourceLocation \"{uri}\" is not a file: URI"))?;
    let bytes = rest.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(byte) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                decoded.push(byte);
                i += 3;
                continue;
            }
        }
        decoded.push(bytes[i]);
        i += 1;
    }
    let path = String::from_utf8(decoded)
        .map_err(|_| format!("resourceLocation \"{uri}\" is not UTF-8 after decoding"))?;
    Ok(PathBuf::from(path))
}
