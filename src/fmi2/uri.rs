//! `fmuResourceLocation` of `fmi2Instantiate` (FMI 2.0 standard, section 2.1.6): a URI
//! (RFC 3986) of the FMU's `resources` folder. Only `file` URIs of local paths are
//! supported: `file:///abs/path`, `file:/abs/path` and `file://localhost/abs/path`, with
//! percent-encoded octets decoded; on Windows the path starts with a drive letter
//! (`file:///C:/fmu/resources`, RFC 8089 appendix E.2).

use std::path::PathBuf;

/// Decodes `%XX` escapes into bytes.
fn percent_decode(text: &str) -> Result<Vec<u8>, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes
                .get(i + 1..i + 3)
                .filter(|h| h.iter().all(u8::is_ascii_hexdigit))
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("invalid percent escape at byte {i} of {text:?}"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    Ok(out)
}

/// The local directory a `file` URI names.
pub fn path_from_file_uri(uri: &str) -> Result<PathBuf, String> {
    let rest = uri
        .strip_prefix("file:")
        .ok_or_else(|| format!("resource location {uri:?} is not a file: URI"))?;
    let path = match rest.strip_prefix("//") {
        Some(authority_and_path) => {
            let slash = authority_and_path
                .find('/')
                .unwrap_or(authority_and_path.len());
            let (host, path) = authority_and_path.split_at(slash);
            if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
                return Err(format!(
                    "resource location {uri:?} names the remote host {host:?}"
                ));
            }
            path
        }
        None => rest,
    };
    if !path.starts_with('/') {
        return Err(format!("resource location {uri:?} is not an absolute path"));
    }
    let path = path.split(['?', '#']).next().unwrap_or(path);
    local_path(percent_decode(path)?).map_err(|why| format!("resource location {uri:?} {why}"))
}

/// The path of the decoded URI path `bytes` (`/abs/path`): its bytes as they are, which is what
/// a Unix file name is.
#[cfg(unix)]
fn local_path(bytes: Vec<u8>) -> Result<PathBuf, String> {
    use std::os::unix::ffi::OsStringExt;
    Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
}

/// The path of the decoded URI path `bytes` (`/C:/abs/path`): UTF-8 (RFC 3986 section 2.5)
/// with the slash before the drive letter dropped; a path without a drive letter is refused,
/// as Windows would take it relative to the current drive.
#[cfg(windows)]
fn local_path(bytes: Vec<u8>) -> Result<PathBuf, String> {
    let text = String::from_utf8(bytes).map_err(|_| "is not UTF-8".to_string())?;
    let drive = text.as_bytes();
    if !(drive.len() >= 4 && drive[1].is_ascii_alphabetic() && drive[2] == b':' && drive[3] == b'/')
    {
        return Err("names no drive (file:///C:/...)".into());
    }
    Ok(PathBuf::from(&text[1..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepted_forms() {
        for uri in [
            "file:///tmp/fmu/resources",
            "file:/tmp/fmu/resources",
            "file://localhost/tmp/fmu/resources",
        ] {
            assert_eq!(
                path_from_file_uri(uri).unwrap(),
                PathBuf::from("/tmp/fmu/resources"),
                "{uri}"
            );
        }
        assert_eq!(
            path_from_file_uri("file:///a/b/").unwrap(),
            PathBuf::from("/a/b/")
        );
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(
            path_from_file_uri("file:///tmp/my%20fmu/r%C3%A9s%25").unwrap(),
            PathBuf::from("/tmp/my fmu/rés%")
        );
        assert!(path_from_file_uri("file:///tmp/%2").is_err());
        assert!(path_from_file_uri("file:///tmp/%zz").is_err());
        assert!(path_from_file_uri("file:///tmp/%+1").is_err());
    }

    #[test]
    fn rejected_forms() {
        for uri in [
            "http://x/y",
            "/tmp/x",
            "file://server/share",
            "file:relative/path",
            "file://",
        ] {
            assert!(path_from_file_uri(uri).is_err(), "{uri} accepted");
        }
    }
}
