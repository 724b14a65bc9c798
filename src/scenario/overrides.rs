//! `--set a.b.c=VALUE`: override a scenario value by its dotted path.
//!
//! Path segments name table keys; for arrays of tables a segment is an
//! index (`bodies.0`) or the `name` of an element (`bodies.bar`). VALUE is
//! parsed as a TOML value (`0.05`, `true`, `[1, 2, 3]`, `"text"`), and taken
//! as a string when it does not parse. The bare word `none` removes the key
//! (or the array element) instead, e.g. `--set time.end_time=none` so that
//! `--set time.steps=10` can replace a file's end time; a quoted `"none"`
//! is the string.

use super::ScenarioError;

/// Apply one `KEY=VALUE` assignment to the parsed TOML table.
pub fn apply_override(root: &mut toml::Table, assignment: &str) -> Result<(), ScenarioError> {
    let err = |message: String| ScenarioError::Override {
        assignment: assignment.to_string(),
        message,
    };
    let (key, raw) = assignment
        .split_once('=')
        .ok_or_else(|| err("expected KEY=VALUE".into()))?;
    let key = key.trim();
    if key.is_empty() {
        return Err(err("empty key".into()));
    }
    let unset = raw.trim() == "none";
    let value = parse_value(raw.trim());
    let segs: Vec<&str> = key.split('.').collect();
    let not_set = || err(format!("`{key}` is not set, so there is nothing to remove"));
    let mut cur: &mut toml::Value = {
        let first = segs[0];
        if segs.len() == 1 {
            if unset {
                root.remove(first).ok_or_else(not_set)?;
            } else {
                root.insert(first.to_string(), value);
            }
            return Ok(());
        }
        if unset {
            root.get_mut(first).ok_or_else(not_set)?
        } else {
            root.entry(first.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        }
    };
    for (i, seg) in segs.iter().enumerate().skip(1) {
        let last = i == segs.len() - 1;
        let here = segs[..i].join(".");
        match cur {
            toml::Value::Table(t) => {
                if last {
                    if unset {
                        t.remove(*seg).ok_or_else(not_set)?;
                    } else {
                        t.insert(seg.to_string(), value);
                    }
                    return Ok(());
                }
                cur = if unset {
                    t.get_mut(*seg).ok_or_else(not_set)?
                } else {
                    t.entry(seg.to_string())
                        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                };
            }
            toml::Value::Array(a) => {
                let idx = match seg.parse::<usize>() {
                    Ok(n) => n,
                    Err(_) => a
                        .iter()
                        .position(|v| v.get("name").and_then(|n| n.as_str()) == Some(seg))
                        .ok_or_else(|| err(format!("`{here}` has no element named `{seg}`")))?,
                };
                let len = a.len();
                if idx >= len {
                    return Err(err(format!("`{here}` has {len} elements, no index {idx}")));
                }
                if last && unset {
                    a.remove(idx);
                    return Ok(());
                }
                let slot = &mut a[idx];
                if last {
                    *slot = value;
                    return Ok(());
                }
                cur = slot;
            }
            _ => return Err(err(format!("`{here}` is a value, not a table"))),
        }
    }
    Ok(())
}

fn parse_value(raw: &str) -> toml::Value {
    let doc = format!("v = {raw}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| toml::Value::String(raw.into())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        text.parse().unwrap()
    }

    #[test]
    fn none_removes_a_key_or_an_element() {
        let mut t = table("[time]\ndt = 1.0\nend_time = 4.0\n[[bc]]\nv = 1\n[[bc]]\nv = 2\n");
        apply_override(&mut t, "time.end_time=none").unwrap();
        apply_override(&mut t, "time.steps=10").unwrap();
        assert_eq!(t["time"].get("end_time"), None);
        assert_eq!(t["time"]["steps"].as_integer(), Some(10));
        apply_override(&mut t, "bc.0=none").unwrap();
        assert_eq!(t["bc"].as_array().unwrap().len(), 1);
        assert_eq!(t["bc"][0]["v"].as_integer(), Some(2));
        // A quoted "none" is the string; an absent key is an error, and
        // no table is created on the way to it.
        apply_override(&mut t, "title=\"none\"").unwrap();
        assert_eq!(t["title"].as_str(), Some("none"));
        let e = apply_override(&mut t, "output.every=none").unwrap_err();
        assert!(e.to_string().contains("`output.every` is not set"), "{e}");
        assert!(t.get("output").is_none());
    }
}
