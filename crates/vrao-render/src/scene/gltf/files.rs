//! The bytes of a glTF and of the files it names: the GLB container, buffers and data or
//! file URIs.

use super::MAX_FILE_BYTES;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Reads `file` (the glTF itself or a file it names), refusing files over [`MAX_FILE_BYTES`].
/// Errors name `gltf`, the file the user gave, and `file` when it differs.
pub(super) fn read_bounded(gltf: &Path, file: &Path) -> Result<Vec<u8>> {
    let what = if gltf == file { String::new() } else { format!("{}: ", file.display()) };
    let size = std::fs::metadata(file).map_err(|e| Error::in_file(gltf, format!("{what}cannot read: {e}")))?.len();
    if size > MAX_FILE_BYTES {
        return Err(Error::in_file(gltf, format!("{what}{size} bytes, more than vrao's limit of {MAX_FILE_BYTES}")));
    }
    std::fs::read(file).map_err(|e| Error::in_file(gltf, format!("{what}cannot read: {e}")))
}

/// The JSON chunk and the optional BIN chunk of a GLB container, checked here (the
/// crate's parser trusts the header's lengths).
pub(super) fn split_glb<'a>(path: &Path, bytes: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>)> {
    let bad = |message: String| Error::in_file(path, message);
    let word = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(bad(format!("truncated .glb: {} bytes, shorter than the 12-byte header", bytes.len())));
    };
    if version != 2 {
        return Err(bad(format!(".glb container version {version}; vrao reads glTF 2.0 (version 2)")));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(bad(format!("truncated .glb: the header says {length} bytes, the file has {}", bytes.len())));
    }
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < length {
        let (Some(chunk_length), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(bad(format!("truncated .glb: chunk header at byte {at} runs past the end")));
        };
        let start = at + 8;
        let end = start.checked_add(chunk_length as usize).filter(|&e| e <= length).ok_or_else(|| {
            bad(format!("truncated .glb: chunk at byte {at} says {chunk_length} bytes, past the end ({length})"))
        })?;
        chunks.push((kind, &bytes[start..end]));
        at = end;
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    match chunks.first() {
        Some(&(JSON, json)) => Ok((json, chunks.get(1).filter(|c| c.0 == BIN).map(|c| c.1))),
        _ => Err(bad("not a valid .glb: the first chunk is not JSON".into())),
    }
}

/// The bytes of every buffer: the GLB's BIN chunk, a data URI or a file beside the glTF.
pub(super) fn load_buffers(path: &Path, document: &::gltf::Document, mut bin: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            ::gltf::buffer::Source::Bin => bin.take().ok_or_else(|| {
                Error::in_file(path, format!("buffer {i} refers to the .glb's binary chunk, which is missing"))
            })?,
            ::gltf::buffer::Source::Uri(uri) => {
                resolve_uri(path, uri).map_err(|m| Error::in_file(path, format!("buffer {i}: {m}")))?
            }
        };
        if data.len() < buffer.length() {
            let message = format!("buffer {i} has {} bytes, the file says {}", data.len(), buffer.length());
            return Err(Error::in_file(path, message));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// The bytes a URI names: a base64 data URI, or a file relative to the glTF's folder.
pub(super) fn resolve_uri(path: &Path, uri: &str) -> std::result::Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest.split_once(',').ok_or("data URI without a ',' before its data")?;
        if !header.ends_with(";base64") {
            return Err("data URI is not base64 (';base64,' expected)".into());
        }
        if payload.len() as u64 > MAX_FILE_BYTES / 3 * 4 {
            return Err(format!("data URI of {} characters, over vrao's limit", payload.len()));
        }
        return decode_base64(payload).ok_or_else(|| "data URI holds invalid base64".to_string());
    }
    if uri.contains("://") {
        return Err(format!("URI '{uri}' is not a file beside the glTF (vrao reads no network)"));
    }
    let relative = percent_decode(uri).ok_or_else(|| format!("URI '{uri}' has a bad %-escape"))?;
    let file = path.parent().unwrap_or(Path::new("")).join(relative);
    if !file.is_file() {
        return Err(format!("file '{uri}' not found (looked for {})", file.display()));
    }
    read_bounded(path, &file).map_err(|e| match e {
        Error::Input { message, .. } => message,
        other => other.to_string(),
    })
}

/// Standard base64 (RFC 4648) with optional padding; `None` for any other character.
pub fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let digit = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let body = text.trim_end_matches('=').as_bytes();
    if text.len() - body.len() > 2 || body.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    for chunk in body.chunks(4) {
        let mut bits = 0u32;
        for &c in chunk {
            bits = (bits << 6) | digit(c)?;
        }
        bits <<= 6 * (4 - chunk.len()) as u32;
        let bytes = bits.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// `%XX` escapes decoded (URIs in glTF are percent-encoded); `None` for a broken escape.
fn percent_decode(uri: &str) -> Option<PathBuf> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    Some(PathBuf::from(String::from_utf8(out).ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_with_and_without_padding() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("aGk=").unwrap(), b"hi");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("aGk*").is_none());
        assert!(decode_base64("a").is_none());
        assert!(decode_base64("aG===").is_none());
    }

    #[test]
    fn percent_escapes_decode() {
        assert_eq!(percent_decode("my%20file.bin").unwrap(), PathBuf::from("my file.bin"));
        assert!(percent_decode("bad%2").is_none());
        assert!(percent_decode("bad%zz").is_none());
    }

    #[test]
    fn glb_container_is_checked_before_parsing() {
        let p = Path::new("t.glb");
        let err = |bytes: &[u8]| split_glb(p, bytes).unwrap_err().to_string();
        assert!(err(b"glTF\x02\0\0").contains("shorter than the 12-byte header"));
        assert!(err(b"glTF\x01\0\0\0\x0c\0\0\0").contains("version 1"));
        assert!(err(b"glTF\x02\0\0\0\xff\0\0\0").contains("the header says 255 bytes, the file has 12"));
        let mut chunk = b"glTF\x02\0\0\0\x18\0\0\0".to_vec();
        chunk.extend_from_slice(&[100, 0, 0, 0]);
        chunk.extend_from_slice(b"JSON{}  ");
        assert!(err(&chunk).contains("says 100 bytes, past the end"), "{}", err(&chunk));
    }
}
