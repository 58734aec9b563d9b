//! Source positions for scenario errors: byte offsets to line and column, and to
//! the key path (`robots[1].controller.kp_nm_per_rad`) of the value at an offset.

use std::ops::Range;
use toml::de::{DeTable, DeValue};

/// 1-based line and column of a byte offset in `src`.
pub fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(src.len());
    let before = &src[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rfind('\n').map_or(offset, |nl| offset - nl - 1) + 1;
    (line, col)
}

/// The key path of the innermost key or value whose span contains `offset`,
/// e.g. `robots[0].controller.kind`. Empty when the offset is at top level.
pub fn key_path_at(src: &str, offset: usize) -> String {
    let Ok(doc) = DeTable::parse(src) else {
        return String::new();
    };
    let mut path = String::new();
    walk_table(doc.get_ref(), offset, &mut path);
    path
}

fn contains(span: &Range<usize>, offset: usize) -> bool {
    span.start <= offset && offset < span.end.max(span.start + 1)
}

fn walk_table(t: &DeTable<'_>, offset: usize, path: &mut String) -> bool {
    for (k, v) in t.iter() {
        let in_key = contains(&k.span(), offset);
        let in_val = contains(&v.span(), offset);
        if in_key || in_val || value_contains(v.get_ref(), offset) {
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(k.get_ref());
            if !in_key {
                walk_value(v.get_ref(), offset, path);
            }
            return true;
        }
    }
    false
}

fn walk_value(v: &DeValue<'_>, offset: usize, path: &mut String) {
    match v {
        DeValue::Table(t) => {
            walk_table(t, offset, path);
        }
        DeValue::Array(a) => {
            for (i, e) in a.iter().enumerate() {
                if contains(&e.span(), offset) || value_contains(e.get_ref(), offset) {
                    path.push_str(&format!("[{i}]"));
                    walk_value(e.get_ref(), offset, path);
                    return;
                }
            }
        }
        _ => {}
    }
}

/// True when any key or value nested in `v` spans `offset` (array-of-tables
/// entries are not contiguous in the source, so their own spans are not enough).
fn value_contains(v: &DeValue<'_>, offset: usize) -> bool {
    match v {
        DeValue::Table(t) => t.iter().any(|(k, v)| {
            contains(&k.span(), offset)
                || contains(&v.span(), offset)
                || value_contains(v.get_ref(), offset)
        }),
        DeValue::Array(a) => a
            .iter()
            .any(|e| contains(&e.span(), offset) || value_contains(e.get_ref(), offset)),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_nested_paths() {
        let src = "format_version = 1\n[world]\ndt_s = 0.001\n[[robots]]\nname = \"a\"\n[[robots]]\nname = \"b\"\n[robots.controller]\nkind = \"joint_pd\"\n";
        let off = src.find("0.001").unwrap();
        assert_eq!(key_path_at(src, off), "world.dt_s");
        let off = src.find("\"b\"").unwrap();
        assert_eq!(key_path_at(src, off), "robots[1].name");
        let off = src.find("\"joint_pd\"").unwrap();
        assert_eq!(key_path_at(src, off), "robots[1].controller.kind");
        assert_eq!(line_col(src, off), (9, 8));
    }
}

/// The span of the value at a key path such as `robots[1].controller.kind`
/// (the key's span when the path ends at a table), if present in the document.
pub fn span_of_path(src: &str, path: &str) -> Option<Range<usize>> {
    let doc = DeTable::parse(src).ok()?;
    let mut table: &DeTable<'_> = doc.get_ref();
    let mut span = None;
    let parts = split_path(path);
    for (n, part) in parts.iter().enumerate() {
        let (key, idx) = match part.rfind('[') {
            Some(b) if part.ends_with(']') && !part.starts_with('"') => (
                &part[..b],
                part[b + 1..part.len() - 1].parse::<usize>().ok(),
            ),
            _ => (part.trim_matches('"'), None),
        };
        let (k, v) = table.iter().find(|(k, _)| k.get_ref().as_ref() == key)?;
        span = Some(k.span());
        let mut value = v;
        if let Some(i) = idx {
            let DeValue::Array(a) = value.get_ref() else {
                return span;
            };
            value = a.get(i)?;
            span = Some(value.span());
        } else if !matches!(value.get_ref(), DeValue::Table(_)) || n + 1 == parts.len() {
            span = Some(if matches!(value.get_ref(), DeValue::Table(_)) {
                k.span()
            } else {
                value.span()
            });
        }
        match value.get_ref() {
            DeValue::Table(t) => table = t,
            _ => {
                if n + 1 < parts.len() {
                    return span;
                }
            }
        }
    }
    span
}

/// Splits `a.b[2]."c.d"` into `a`, `b[2]`, `"c.d"` (quoted segments keep their dots).
fn split_path(path: &str) -> Vec<String> {
    let mut parts = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    for ch in path.chars() {
        match ch {
            '"' => {
                quoted = !quoted;
                cur.push(ch);
            }
            '.' if !quoted => {
                if !cur.is_empty() {
                    parts.push(std::mem::take(&mut cur));
                }
            }
            _ => cur.push(ch),
        }
    }
    if !cur.is_empty() {
        parts.push(cur);
    }
    parts
}

/// Quotes a key for a key path when it contains a dot.
pub fn path_key(key: &str) -> String {
    if key.contains('.') {
        format!("\"{key}\"")
    } else {
        key.to_string()
    }
}

#[cfg(test)]
mod path_tests {
    use super::*;

    #[test]
    fn span_of_path_finds_values() {
        let src = "[world]\ndt_s = 0.001\n[[robots]]\nname = \"a\"\n[[robots]]\nname = \"b\"\nparams = { \"thigh.length_m\" = -1.0 }\n";
        let s = span_of_path(src, "robots[1].name").unwrap();
        assert_eq!(&src[s], "\"b\"");
        let s = span_of_path(src, "world.dt_s").unwrap();
        assert_eq!(&src[s], "0.001");
        let s = span_of_path(src, "robots[1].params.\"thigh.length_m\"").unwrap();
        assert_eq!(&src[s], "-1.0");
    }
}
