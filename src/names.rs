//! Names that become parts of file paths, and the checks that keep every
//! written file inside its output directory.
//!
//! Robots, herds, terrains, payloads, worlds and studies are named in their
//! files; a name is used in output file names (`plots/<robot>_com.svg`), log
//! channel names and the default output directory (`runs/<world>/`). A name
//! is therefore **1 to [`NAME_MAX_CHARS`] characters of ASCII letters,
//! digits, `_`, `-` and `.`, starting with a letter, a digit or `_`, and
//! without `..`** ([`check_name`]); it can hold no path separator and never
//! climbs out of a directory. Files are then written only under names built
//! by [`safe_file_stem`] and joined by [`join_inside`], which refuses any
//! path that would leave the output directory.

use std::path::{Component, Path, PathBuf};

/// The longest name (characters).
pub const NAME_MAX_CHARS: usize = 64;

/// The character set, as the error messages state it.
pub const NAME_CHARSET: &str =
    "ASCII letters, digits, '_', '-' and '.', starting with a letter, a digit or '_', without '..'";

/// Whether `name` is a valid name (see the module doc); `Err` says why not.
pub fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("must not be empty".into());
    }
    let n = name.chars().count();
    if n > NAME_MAX_CHARS {
        return Err(format!(
            "is {n} characters long; a name has at most {NAME_MAX_CHARS}"
        ));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.')))
    {
        return Err(format!(
            "'{}' contains {c:?}: a name is {NAME_CHARSET}",
            shorten(name)
        ));
    }
    if name.starts_with(['.', '-']) {
        return Err(format!("'{name}' must start with a letter, a digit or '_'"));
    }
    if name.contains("..") {
        return Err(format!("'{name}' must not contain '..'"));
    }
    Ok(())
}

/// A name cut to 40 characters for messages (a rejected name may be huge).
pub fn shorten(name: &str) -> String {
    if name.chars().count() <= 40 {
        name.to_string()
    } else {
        let s: String = name.chars().take(40).collect();
        format!("{s}…")
    }
}

/// A file name stem made from any text: characters outside the name set
/// become `_`, `..` becomes `_.`, a leading `.` or `-` becomes `_`, and it is
/// cut to 120 characters. Valid names come out unchanged.
pub fn safe_file_stem(s: &str) -> String {
    let mut out: String = s
        .chars()
        .take(120)
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    while out.contains("..") {
        out = out.replace("..", "_.");
    }
    if out.is_empty() || out.starts_with(['.', '-']) {
        out.insert(0, '_');
    }
    out
}

/// `dir/name`, where `name` must be one or more plain relative components
/// (no root, no `..`, no `.` prefix tricks): anything else is refused, so a
/// file built from it cannot land outside `dir`.
pub fn join_inside(dir: &Path, name: &str) -> Result<PathBuf, String> {
    let rel = Path::new(name);
    let plain = !name.is_empty()
        && rel
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    if !plain {
        return Err(format!(
            "refusing to write '{}': a file name must stay inside {}",
            shorten(name),
            dir.display()
        ));
    }
    Ok(dir.join(rel))
}

/// Whether `path` lies lexically inside `dir` (both as given, no symbolic
/// links resolved): `path` starts with `dir` and what follows holds only
/// plain components.
pub fn is_inside(dir: &Path, path: &Path) -> bool {
    match path.strip_prefix(dir) {
        Ok(rest) => rest
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir)),
        Err(_) => false,
    }
}

/// A robot name or glob pattern (`*`, `?`, `[abc]`), e.g. `q16-00*`.
#[derive(Debug, Clone)]
pub struct RobotPattern(glob::Pattern);

impl RobotPattern {
    /// Parses `pattern`; an empty or malformed one is an error saying why.
    pub fn new(pattern: &str) -> Result<Self, String> {
        if pattern.trim().is_empty() {
            return Err("an empty robot name or pattern".into());
        }
        glob::Pattern::new(pattern)
            .map(Self)
            .map_err(|e| format!("'{pattern}' is not a name or glob pattern: {e}"))
    }

    /// Whether robot `name` matches.
    pub fn matches(&self, name: &str) -> bool {
        self.0.matches(name)
    }

    /// The pattern as written.
    pub fn as_str(&self) -> &str {
        self.0.as_str()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        for ok in [
            "rex",
            "q16-000",
            "trot_flat",
            "a.b",
            "_x",
            "0",
            &"x".repeat(64),
        ] {
            assert!(check_name(ok).is_ok(), "{ok}");
        }
        for bad in [
            "",
            "../../../X",
            "/abs",
            "a/b",
            "a\\b",
            "..",
            "a..b",
            ".hidden",
            "-flag",
            "with space",
            "é",
            &"x".repeat(65),
        ] {
            assert!(check_name(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn stems_and_joins() {
        assert_eq!(safe_file_stem("rex"), "rex");
        assert_eq!(safe_file_stem("/etc/passwd"), "_etc_passwd");
        for s in ["../../../X_com.svg", "/abs/x", "a/../../b", "..", ""] {
            let st = safe_file_stem(s);
            assert!(join_inside(Path::new("out"), &st).is_ok(), "{st}");
            assert!(!st.contains('/') && !st.contains(".."), "{st}");
        }
        assert!(join_inside(Path::new("out"), "../x").is_err());
        assert!(join_inside(Path::new("out"), "/x").is_err());
        assert!(join_inside(Path::new("out"), "plots/x.svg").is_ok());
        assert!(is_inside(Path::new("out"), Path::new("out/plots/x.svg")));
        assert!(!is_inside(Path::new("out"), Path::new("out/../x")));
        assert!(!is_inside(Path::new("out"), Path::new("/x")));
    }
}
