//! `--set a.b.c=VALUE`: override a scenario value by its dotted path.
//!
//! Path segments name table keys; for arrays of tables a segment is an
//! index (`bodies.0`) or the `name` of an element (`bodies.bar`). VALUE is
//! parsed as a TOML value (`0.05`, `true`, `[1, 2, 3]`, `"text"`), and taken
//! as a string when it does not parse.

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
    let value = parse_value(raw.trim());
    let segs: Vec<&str> = key.split('.').collect();
    let mut cur: &mut toml::Value = {
        let first = segs[0];
        if segs.len() == 1 {
            root.insert(first.to_string(), value);
            return Ok(());
        }
        root.entry(first.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
    };
    for (i, seg) in segs.iter().enumerate().skip(1) {
        let last = i == segs.len() - 1;
        let here = segs[..i].join(".");
        match cur {
            toml::Value::Table(t) => {
                if last {
                    t.insert(seg.to_string(), value);
                    return Ok(());
                }
                cur = t
                    .entry(seg.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()));
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
                let slot = a
                    .get_mut(idx)
                    .ok_or_else(|| err(format!("`{here}` has {len} elements, no index {idx}")))?;
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
