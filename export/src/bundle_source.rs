//! Where an exported library finds its model: an FMU's `resources/bundle.json`, or the bundle
//! appended to the library file itself (a CasADi export, one file).

use std::path::PathBuf;

use twv_ir::Bundle;

/// The bundle in the resources folder at `location` (an FMI `fmuResourceLocation`: a `file:`
/// URI).
pub fn from_resources(location: &str) -> Result<Bundle, String> {
    let dir = file_uri_path(location).ok_or_else(|| {
        format!("fmi2Instantiate: resource location {location:?} is not a file: URI")
    })?;
    let path = dir.join(twv_ir::FMU_RESOURCE);
    let bytes = std::fs::read(&path)
        .map_err(|e| format!("fmi2Instantiate: cannot read {}: {e}", path.display()))?;
    Bundle::parse(&bytes, &path.display().to_string()).map_err(|e| e.to_string())
}

/// The path of a `file:` URI (`file:///a/b%20c`, `file://localhost/a`, `file:/a`), percent
/// escapes decoded.
pub fn file_uri_path(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let path = if let Some(authority) = rest.strip_prefix("//") {
        let slash = authority.find('/')?;
        let host = &authority[..slash];
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return None;
        }
        &authority[slash..]
    } else {
        rest
    };
    let bytes = path.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    use std::os::unix::ffi::OsStringExt;
    Some(PathBuf::from(std::ffi::OsString::from_vec(out)))
}

/// The path of this shared library, from the dynamic loader (`dladdr` of one of its symbols).
pub fn own_file() -> Option<PathBuf> {
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    let symbol = own_file as *const libc::c_void;
    // SAFETY: dladdr only reads the loader's tables; `info` is a valid out-pointer.
    if unsafe { libc::dladdr(symbol, &mut info) } == 0 || info.dli_fname.is_null() {
        return None;
    }
    // SAFETY: a NUL-terminated path owned by the loader, copied at once.
    let name = unsafe { std::ffi::CStr::from_ptr(info.dli_fname) };
    use std::os::unix::ffi::OsStrExt;
    Some(PathBuf::from(std::ffi::OsStr::from_bytes(name.to_bytes())))
}

/// The bundle appended to this library's file (`twv export --casadi`).
pub fn from_own_file() -> Result<Bundle, String> {
    let path = own_file().ok_or("the loader does not say which file this library is")?;
    Bundle::from_trailer(&path).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uris_become_paths() {
        let p = |s| file_uri_path(s).map(|p| p.display().to_string());
        assert_eq!(p("file:///tmp/a%20b/res").as_deref(), Some("/tmp/a b/res"));
        assert_eq!(p("file://localhost/x").as_deref(), Some("/x"));
        assert_eq!(p("file:/x/y").as_deref(), Some("/x/y"));
        assert_eq!(p("file://host/x"), None);
        assert_eq!(p("http://x/y"), None);
        assert_eq!(p("file:///bad%zz%4").as_deref(), Some("/bad%zz%4"));
    }
}
