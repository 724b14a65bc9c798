//! Fuzzing (issue 16): every shipped scenario and Gmsh mesh, mutated at
//! random (seeded, deterministic), must end in a clean error (an `Err` with
//! a message) or a valid model, never a panic, a hang or an unbounded
//! allocation.
//!
//! - `mutated_scenarios_end_in_an_error_or_a_model`: in-process, the way
//!   `fdem check` works (`scenario::parse_str` with `--set` overrides, then
//!   `Model::from_scenario`), every `panic` caught with `catch_unwind`.
//! - `mutated_meshes_end_in_an_error_or_a_model`: the same for the Gmsh
//!   files in `scenarios/meshes` (ASCII) and a binary MSH 4.1 written here,
//!   through `mesh::gmsh::read_msh` and a model using the mesh.
//! - `mutated_scenarios_through_the_binary`: a smaller sample through
//!   `fdem run` (1 and 2 ranks), with a short run forced: exit status 0 or
//!   1, one error message, no panic, a time limit, no output left behind
//!   by a run refused before its first step.
//!
//! A failing case prints its scenario (or mesh), case number, seed and the
//! mutated input; `FDEM_FUZZ_ONLY=<name>:<case>` re-runs just that case.
//! `FDEM_FUZZ_SCALE=<x>` multiplies every case count (CI runs x = 1; a
//! longer campaign, e.g. x = 10, runs the same cases and more).
//! The case being run in-process is also written to
//! `target/test-output/fuzz/current-*.txt`, which names the culprit if the
//! process dies (an allocation failure aborts, it does not unwind).

use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::io::Write as _;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Once};
use std::time::{Duration, Instant};

use crate::common::*;
use rand::seq::SliceRandom;
use rand::Rng;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use toml::Value;

/// Seed of every run; a case's own seed mixes in its input and number.
const SEED: u64 = 0x1616_f022_d0e5_0001;
/// Mutated cases per shipped scenario (in-process).
const CASES_PER_SCENARIO: usize = 240;
/// The element limit while a case builds its model in-process
/// ([`fdem::mesh::with_element_limit`]): a mutation that makes a valid but
/// huge model (a bar widened 10,000 times: 15 M tets, 26 s to build) ends
/// in the limit's error at once. Every reduced base builds under it
/// (asserted before its cases).
const FUZZ_ELEMENT_LIMIT: usize = 500_000;
/// Mutated cases per Gmsh file (in-process).
const CASES_PER_MESH: usize = 2000;
/// Mutated scenarios run through the binary.
const BINARY_CASES: usize = 100;
/// `n` cases scaled by `FDEM_FUZZ_SCALE` (default 1; at least one case).
fn scaled(n: usize) -> usize {
    let x = std::env::var("FDEM_FUZZ_SCALE").map_or(1.0, |v| {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && *x > 0.0)
            .unwrap_or_else(|| panic!("FDEM_FUZZ_SCALE={v}: expected a positive number"))
    });
    ((n as f64 * x).round() as usize).max(1)
}
/// A single in-process case running longer than this is a hang.
const CASE_LIMIT: Duration = Duration::from_secs(30);
/// A binary run longer than this is a hang.
const RUN_LIMIT: Duration = Duration::from_secs(60);

// ------------------------------------------------------------------ harness

thread_local! {
    /// Panics on this thread are expected to be caught: record, don't print.
    static CATCHING: Cell<bool> = const { Cell::new(false) };
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// A panic hook that records the panic of a fuzzing thread (message and
/// location) instead of printing it, and leaves other threads' panics
/// (test failures) to the default hook.
fn install_panic_hook() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if CATCHING.with(Cell::get) {
                LAST_PANIC.with(|p| *p.borrow_mut() = Some(info.to_string()));
            } else {
                default(info);
            }
        }));
    });
}

/// One in-process case: what it is, for the failure report.
#[derive(Clone)]
struct Case {
    input: String,
    number: usize,
    seed: u64,
    /// What was done to the input.
    mutations: Vec<String>,
    /// The mutated input (text, or a description of the bytes).
    text: String,
    sets: Vec<String>,
}

impl std::fmt::Display for Case {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} case {} (seed {:#x}; re-run alone with FDEM_FUZZ_ONLY={}:{})",
            self.input, self.number, self.seed, self.input, self.number
        )?;
        writeln!(f, "mutations: {:?}", self.mutations)?;
        if !self.sets.is_empty() {
            writeln!(f, "--set {:?}", self.sets)?;
        }
        writeln!(f, "---- mutated input ----\n{}\n---- end ----", self.text)
    }
}

/// Whether `FDEM_FUZZ_ONLY` (`name:case`) selects this case.
fn selected(input: &str, number: usize) -> bool {
    match std::env::var("FDEM_FUZZ_ONLY") {
        Ok(only) => only == format!("{input}:{number}"),
        Err(_) => true,
    }
}

/// Runs cases in-process, with a watchdog for hangs, and counts outcomes.
struct Runner {
    current: Arc<Mutex<Option<(Instant, String)>>>,
    record: PathBuf,
    cases: usize,
    ok: usize,
    errors: usize,
    failures: Vec<String>,
    /// Error messages seen, by their first words (a summary for the log).
    kinds: BTreeMap<String, usize>,
    /// The slowest cases: (seconds, input:case).
    slowest: Vec<(f64, String)>,
}

impl Runner {
    fn new(name: &str) -> Self {
        install_panic_hook();
        let dir = root().join("target").join("test-output").join("fuzz");
        std::fs::create_dir_all(&dir).unwrap();
        let current: Arc<Mutex<Option<(Instant, String)>>> = Arc::new(Mutex::new(None));
        let watched = Arc::downgrade(&current);
        std::thread::spawn(move || {
            while let Some(current) = watched.upgrade() {
                if let Some((start, case)) = current.lock().unwrap().as_ref() {
                    if start.elapsed() > CASE_LIMIT {
                        // Unwinding cannot stop the looping thread: report and exit.
                        let _ = writeln!(
                            std::io::stderr(),
                            "fuzz: HANG (over {CASE_LIMIT:?}) in\n{case}"
                        );
                        std::process::exit(1);
                    }
                }
                drop(current);
                std::thread::sleep(Duration::from_millis(250));
            }
        });
        Runner {
            current,
            record: dir.join(format!("current-{name}.txt")),
            cases: 0,
            ok: 0,
            errors: 0,
            failures: Vec::new(),
            kinds: BTreeMap::new(),
            slowest: Vec::new(),
        }
    }

    /// Runs `f`; `Err` must carry a message, a panic is a failure.
    fn run(&mut self, case: &Case, f: impl FnOnce() -> Result<(), String>) {
        let report = case.to_string();
        let _ = std::fs::write(&self.record, &report);
        *self.current.lock().unwrap() = Some((Instant::now(), report));
        LAST_PANIC.with(|p| p.borrow_mut().take());
        CATCHING.with(|c| c.set(true));
        let start = Instant::now();
        let outcome = std::panic::catch_unwind(AssertUnwindSafe(f));
        let took = start.elapsed().as_secs_f64();
        CATCHING.with(|c| c.set(false));
        self.slowest
            .push((took, format!("{}:{}", case.input, case.number)));
        self.slowest.sort_by(|a, b| b.0.total_cmp(&a.0));
        self.slowest.truncate(5);
        *self.current.lock().unwrap() = None;
        self.cases += 1;
        if std::env::var("FDEM_FUZZ_ONLY").is_ok() {
            let shown = match &outcome {
                Ok(r) => format!("{r:?}"),
                Err(_) => "panic".into(),
            };
            eprintln!("{case}outcome after {took:.3} s: {shown}");
        }
        match outcome {
            Ok(Ok(())) => self.ok += 1,
            Ok(Err(msg)) => {
                self.errors += 1;
                if msg.trim().is_empty() {
                    self.failures
                        .push(format!("empty error message for {case}"));
                }
                // The last line says what (toml puts the location first);
                // numbers and quoted names stripped, to group the messages.
                let last = msg.lines().rfind(|l| !l.trim().is_empty()).unwrap_or("");
                let kind: String = last
                    .split(['`', '\'', '"'])
                    .step_by(2)
                    .collect::<Vec<_>>()
                    .join("_")
                    .chars()
                    .filter(|c| !c.is_ascii_digit())
                    .take(70)
                    .collect();
                *self.kinds.entry(kind).or_default() += 1;
            }
            Err(payload) => {
                let msg = LAST_PANIC
                    .with(|p| p.borrow_mut().take())
                    .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "(no message)".into());
                self.failures.push(format!("PANIC: {msg}\nin {case}"));
            }
        }
    }

    fn finish(self, what: &str, started: Instant) {
        eprintln!(
            "fuzz {what}: {} cases in {:.1} s: {} valid, {} clean errors, {} failures",
            self.cases,
            started.elapsed().as_secs_f64(),
            self.ok,
            self.errors,
            self.failures.len()
        );
        let mut kinds: Vec<_> = self.kinds.iter().collect();
        kinds.sort_by(|a, b| b.1.cmp(a.1));
        for (k, n) in kinds.iter().take(12) {
            eprintln!("  {n:6}  {k}");
        }
        for (t, c) in &self.slowest {
            eprintln!("  slowest: {c} {t:.2} s");
        }
        let _ = std::fs::remove_file(&self.record);
        assert!(
            self.failures.is_empty(),
            "{} of {} cases failed; the first:\n{}",
            self.failures.len(),
            self.cases,
            self.failures[0]
        );
    }
}

/// The seed of case `number` of `input`.
fn case_seed(input: &str, number: usize) -> u64 {
    let mut h = SEED;
    for b in input.bytes().chain((number as u64).to_le_bytes()) {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

// ------------------------------------------------------ TOML mutations

#[derive(Clone, Debug)]
enum Seg {
    Key(String),
    Index(usize),
}

/// Paths to every value below the root.
fn paths(v: &Value, prefix: &mut Vec<Seg>, out: &mut Vec<Vec<Seg>>) {
    match v {
        Value::Table(t) => {
            for (k, x) in t {
                prefix.push(Seg::Key(k.clone()));
                out.push(prefix.clone());
                paths(x, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                prefix.push(Seg::Index(i));
                out.push(prefix.clone());
                paths(x, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

fn get<'a>(v: &'a Value, path: &[Seg]) -> Option<&'a Value> {
    let mut cur = v;
    for s in path {
        cur = match (s, cur) {
            (Seg::Key(k), Value::Table(t)) => t.get(k)?,
            (Seg::Index(i), Value::Array(a)) => a.get(*i)?,
            _ => return None,
        };
    }
    Some(cur)
}

fn get_mut<'a>(v: &'a mut Value, path: &[Seg]) -> Option<&'a mut Value> {
    let mut cur = v;
    for s in path {
        cur = match (s, cur) {
            (Seg::Key(k), Value::Table(t)) => t.get_mut(k)?,
            (Seg::Index(i), Value::Array(a)) => a.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(cur)
}

fn dotted(path: &[Seg]) -> String {
    path.iter()
        .map(|s| match s {
            Seg::Key(k) => k.clone(),
            Seg::Index(i) => i.to_string(),
        })
        .collect::<Vec<_>>()
        .join(".")
}

/// Numbers that break things: zero, signs, extremes, non-finite values.
fn extreme_number(rng: &mut Pcg64) -> Value {
    let floats = [
        0.0,
        -0.0,
        -1.0,
        1e-300,
        5e-324,
        1e-9,
        1e9,
        1e300,
        -1e300,
        f64::MAX,
        f64::MIN,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.5,
        1.0,
        2.0,
    ];
    let ints = [
        0,
        -1,
        1,
        2,
        i64::MAX,
        i64::MIN,
        u32::MAX as i64 + 1,
        1 << 53,
        1_000_000_000,
        -1_000_000_000,
    ];
    if rng.gen_bool(0.6) {
        Value::Float(*floats.choose(rng).unwrap())
    } else {
        Value::Integer(*ints.choose(rng).unwrap())
    }
}

/// A value near `v`: scaled by powers of ten (far enough that a scaled mesh
/// size is either coarse or refused), negated, off by one.
fn nearby_number(v: &Value, rng: &mut Pcg64) -> Option<Value> {
    let k = *[-12, -6, -3, 3, 6, 12].choose(rng).unwrap();
    match v {
        Value::Float(x) => Some(Value::Float(match rng.gen_range(0..3) {
            0 => x * 10f64.powi(k),
            1 => -x,
            _ => x + 1.0,
        })),
        Value::Integer(n) => Some(Value::Integer(match rng.gen_range(0..4) {
            0 => n.saturating_mul(10i64.saturating_pow(k.unsigned_abs())),
            1 => -n,
            2 => n.saturating_add(1),
            _ => n.saturating_sub(1),
        })),
        _ => None,
    }
}

/// A value of another type than `v`.
fn other_type(v: &Value, rng: &mut Pcg64) -> Value {
    loop {
        let x = match rng.gen_range(0..7) {
            0 => Value::String("x".into()),
            1 => Value::Integer(3),
            2 => Value::Float(0.25),
            3 => Value::Boolean(true),
            4 => Value::Array(vec![Value::Float(1.0), Value::String("a".into())]),
            5 => Value::Table(toml::Table::new()),
            _ => Value::Datetime("1979-05-27T07:32:00Z".parse().unwrap()),
        };
        if std::mem::discriminant(&x) != std::mem::discriminant(v) {
            return x;
        }
    }
}

/// Strings found in the document, plus awkward ones.
fn string_pool(v: &Value, out: &mut Vec<String>) {
    match v {
        Value::String(s) => out.push(s.clone()),
        Value::Table(t) => t.values().for_each(|x| string_pool(x, out)),
        Value::Array(a) => a.iter().for_each(|x| string_pool(x, out)),
        _ => {}
    }
}

fn awkward_string(pool: &[String], rng: &mut Pcg64) -> String {
    match rng.gen_range(0..9) {
        0 => String::new(),
        1 => "a.b".into(),
        2 => "x".repeat(rng.gen_range(100..5000)),
        3 => "meshes/nut-192.msh".into(),
        4 => "meshes/no-such-file.msh".into(),
        5 => ".".into(),
        6 => "é\u{0}\t\"'/:".into(),
        _ => pool.choose(rng).cloned().unwrap_or_default(),
    }
}

/// Numbers found in the document (a value moved to another key).
fn number_pool(v: &Value, out: &mut Vec<Value>) {
    match v {
        Value::Integer(_) | Value::Float(_) => out.push(v.clone()),
        Value::Table(t) => t.values().for_each(|x| number_pool(x, out)),
        Value::Array(a) => a.iter().for_each(|x| number_pool(x, out)),
        _ => {}
    }
}

/// One structural mutation of a parsed scenario; returns its description.
fn mutate_value(doc: &mut Value, rng: &mut Pcg64) -> Option<String> {
    let mut all = Vec::new();
    paths(doc, &mut Vec::new(), &mut all);
    let mut strings = Vec::new();
    string_pool(doc, &mut strings);
    let mut numbers = Vec::new();
    number_pool(doc, &mut numbers);
    // Leaves (numbers, strings, ...) more often than whole tables.
    let leaves: Vec<&Vec<Seg>> = all
        .iter()
        .filter(|p| !matches!(get(doc, p), Some(Value::Table(_) | Value::Array(_))))
        .collect();
    let path = if rng.gen_bool(0.75) && !leaves.is_empty() {
        (*leaves.choose(rng)?).clone()
    } else {
        all.choose(rng)?.clone()
    };
    let name = dotted(&path);
    let (parent_path, last) = path.split_at(path.len() - 1);
    let kind = rng.gen_range(0..10);
    if kind == 0 {
        // Delete the key (or array element).
        match (get_mut(doc, parent_path)?, &last[0]) {
            (Value::Table(t), Seg::Key(k)) => {
                t.remove(k);
            }
            (Value::Array(a), Seg::Index(i)) => {
                a.remove(*i);
            }
            _ => return None,
        }
        return Some(format!("delete {name}"));
    }
    if kind == 1 {
        // Duplicate an array element (a table of `[[bodies]]`, a number).
        let (parent_path, idx) = match (&last[0], get_mut(doc, parent_path)) {
            (Seg::Index(i), Some(Value::Array(_))) => (parent_path.to_vec(), *i),
            _ => {
                // The nearest enclosing array, if any.
                let at = path.iter().rposition(|s| matches!(s, Seg::Index(_)))?;
                let Seg::Index(i) = path[at] else {
                    return None;
                };
                (path[..at].to_vec(), i)
            }
        };
        let Some(Value::Array(a)) = get_mut(doc, &parent_path) else {
            return None;
        };
        let copy = a[idx].clone();
        a.insert(idx + 1, copy);
        return Some(format!("duplicate {}.{idx}", dotted(&parent_path)));
    }
    if kind == 2 {
        // Rename the key (an unknown key) or add one.
        if let (Value::Table(t), Seg::Key(k)) = (get_mut(doc, parent_path)?, &last[0]) {
            let v = t.remove(k)?;
            let new = if rng.gen_bool(0.5) {
                format!("{k}x")
            } else {
                k.chars().skip(1).collect()
            };
            t.insert(new.clone(), v);
            return Some(format!("rename {name} -> {new}"));
        }
        return None;
    }
    let target = get_mut(doc, &path)?;
    let before = target.clone();
    *target = match kind {
        3 => other_type(&before, rng),
        4 | 5 => extreme_number(rng),
        6 => nearby_number(&before, rng).unwrap_or_else(|| extreme_number(rng)),
        7 => match &before {
            Value::String(_) => Value::String(awkward_string(&strings, rng)),
            Value::Array(a) if rng.gen_bool(0.5) && !a.is_empty() => {
                Value::Array(a[..a.len() - 1].to_vec())
            }
            Value::Array(a) => {
                let mut a = a.clone();
                a.push(a.first().cloned().unwrap_or(Value::Float(1.0)));
                Value::Array(a)
            }
            _ => numbers.choose(rng).cloned().unwrap_or(Value::Float(0.0)),
        },
        8 => numbers.choose(rng).cloned().unwrap_or(Value::Float(0.0)),
        _ => Value::Float(
            *[f64::NAN, f64::INFINITY, f64::NEG_INFINITY]
                .choose(rng)
                .unwrap(),
        ),
    };
    Some(format!("{name}: {before} -> {target}"))
}

/// Line-level and byte-level damage to the text.
fn mutate_text(text: &str, rng: &mut Pcg64) -> (String, String) {
    let lines: Vec<&str> = text.lines().collect();
    let cut = |i: usize| {
        let mut i = i.min(text.len());
        while !text.is_char_boundary(i) {
            i -= 1;
        }
        i
    };
    match rng.gen_range(0..6) {
        0 => {
            let at = cut(rng.gen_range(0..=text.len()));
            (text[..at].to_string(), format!("truncate at byte {at}"))
        }
        1 if !lines.is_empty() => {
            // Duplicate a table: its header line up to the next header.
            let headers: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].trim_start().starts_with('['))
                .collect();
            let Some(&h) = headers.choose(rng) else {
                return (text.to_string(), "no table to duplicate".into());
            };
            let end = headers
                .iter()
                .copied()
                .find(|&j| j > h)
                .unwrap_or(lines.len());
            let mut out: Vec<&str> = lines.clone();
            let block: Vec<&str> = lines[h..end].to_vec();
            let at = rng.gen_range(0..=out.len());
            out.splice(at..at, block);
            (
                out.join("\n"),
                format!("duplicate table `{}` at line {at}", lines[h].trim()),
            )
        }
        2 if !lines.is_empty() => {
            let i = rng.gen_range(0..lines.len());
            let mut out = lines.clone();
            out.remove(i);
            (out.join("\n"), format!("delete line {}", i + 1))
        }
        3 if lines.len() > 1 => {
            let (i, j) = (rng.gen_range(0..lines.len()), rng.gen_range(0..lines.len()));
            let mut out = lines.clone();
            out.swap(i, j);
            (
                out.join("\n"),
                format!("swap lines {} and {}", i + 1, j + 1),
            )
        }
        _ => {
            // Flip bits of a few bytes; invalid UTF-8 is replaced.
            let mut b = text.as_bytes().to_vec();
            let n = rng.gen_range(1..=4);
            for _ in 0..n {
                if b.is_empty() {
                    break;
                }
                let i = rng.gen_range(0..b.len());
                b[i] ^= 1 << rng.gen_range(0..8);
            }
            (
                String::from_utf8_lossy(&b).into_owned(),
                format!("flip {n} byte(s)"),
            )
        }
    }
}

/// A `--set KEY=VALUE` with a key of the document and a value that may be
/// of the wrong type or not TOML at all.
fn random_set(doc: &Value, rng: &mut Pcg64) -> String {
    let mut all = Vec::new();
    paths(doc, &mut Vec::new(), &mut all);
    let key = match all.choose(rng) {
        Some(p) if rng.gen_bool(0.9) => dotted(p),
        _ => "no.such.key".into(),
    };
    let value = match rng.gen_range(0..8) {
        0 => "nan".to_string(),
        1 => "-1".into(),
        2 => "1e300".into(),
        3 => "\"text\"".into(),
        4 => "[1.0, ".into(),
        5 => String::new(),
        6 => "{ a = 1 }".into(),
        _ => match extreme_number(rng) {
            Value::Float(x) if x.is_nan() => "nan".into(),
            Value::Float(x) if x.is_infinite() => (if x > 0.0 { "inf" } else { "-inf" }).into(),
            v => v.to_string(),
        },
    };
    if rng.gen_bool(0.05) {
        key // no `=`
    } else {
        format!("{key}={value}")
    }
}

/// A mutated scenario: text and `--set` overrides, with what was done.
struct Mutated {
    text: String,
    sets: Vec<String>,
    mutations: Vec<String>,
}

fn mutate_scenario(base: &str, rng: &mut Pcg64, cap: Option<&dyn Fn(&mut Value)>) -> Mutated {
    let mut doc: Value = Value::Table(toml::from_str(base).expect("shipped scenario parses"));
    let mut mutations = Vec::new();
    for _ in 0..rng.gen_range(1..=2) {
        if let Some(m) = mutate_value(&mut doc, rng) {
            mutations.push(m);
        }
    }
    if let Some(cap) = cap {
        cap(&mut doc);
    }
    let mut text = match toml::to_string(&doc) {
        Ok(t) => t,
        Err(e) => {
            mutations.push(format!("(not serialisable: {e}; original text used)"));
            base.to_string()
        }
    };
    if rng.gen_bool(0.15) {
        let (t, m) = mutate_text(&text, rng);
        text = t;
        mutations.push(m);
    }
    let sets = if rng.gen_bool(0.15) {
        (0..rng.gen_range(1..=2))
            .map(|_| random_set(&doc, rng))
            .collect()
    } else {
        Vec::new()
    };
    Mutated {
        text,
        sets,
        mutations,
    }
}

/// Parse, validate and build the model, as `fdem check` does (under the
/// [`FUZZ_ELEMENT_LIMIT`]).
fn check_in_process(text: &str, path: &Path, sets: &[String]) -> Result<(), String> {
    fdem::mesh::with_element_limit(FUZZ_ELEMENT_LIMIT, || {
        let sc = fdem::scenario::parse_str(text, path, sets).map_err(|e| e.to_string())?;
        let model = fdem::model::Model::from_scenario(&sc).map_err(|e| e.to_string())?;
        model.whole_mesh().map_err(|e| e.to_string())?;
        Ok(())
    })
}

fn shipped_scenarios() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("scenarios"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    assert!(v.len() >= 20, "only {} scenarios", v.len());
    v
}

fn stem(p: &Path) -> String {
    p.file_stem().unwrap().to_string_lossy().into_owned()
}

#[test]
fn mutated_scenarios_end_in_an_error_or_a_model() {
    let started = Instant::now();
    let mut runner = Runner::new("scenario");
    for path in shipped_scenarios() {
        let name = stem(&path);
        let base = reduced_base(&path, false);
        // The unmutated base is not refused by the limit (else every case
        // would end there); a later stage may lack its checkpoint.
        if let Err(e) = check_in_process(&base, &path, &[]) {
            assert!(
                !e.contains("fdem's limit"),
                "{name}: the base exceeds the fuzz's element limit: {e}"
            );
        }
        let cases = scaled(CASES_PER_SCENARIO);
        let t0 = Instant::now();
        for number in 0..cases {
            if !selected(&name, number) {
                continue;
            }
            let seed = case_seed(&name, number);
            let mut rng = Pcg64::seed_from_u64(seed);
            let m = mutate_scenario(&base, &mut rng, None);
            let case = Case {
                input: name.clone(),
                number,
                seed,
                mutations: m.mutations,
                text: m.text.clone(),
                sets: m.sets.clone(),
            };
            runner.run(&case, || check_in_process(&m.text, &path, &m.sets));
        }
        eprintln!(
            "  {name}: {cases} cases, {:.2} s",
            t0.elapsed().as_secs_f64()
        );
    }
    assert!(
        runner.cases >= scaled(9_000) || std::env::var("FDEM_FUZZ_ONLY").is_ok(),
        "only {} cases",
        runner.cases
    );
    runner.finish("scenarios (in-process)", started);
}

// ------------------------------------------------------ Gmsh mutations

/// Writes `mesh` as a binary MSH 4.1 file (little endian, size_t = 8), from
/// the format's specification: one volume entity (physical volume `all`),
/// one surface entity and physical surface per face set, all nodes in one
/// block on the volume.
fn binary_msh(mesh: &fdem::mesh::TetMesh) -> Vec<u8> {
    struct Bin(Vec<u8>);
    impl Bin {
        fn s(&mut self, t: &str) {
            self.0.extend_from_slice(t.as_bytes());
        }
        fn sz(&mut self, v: usize) {
            self.0.extend_from_slice(&(v as u64).to_le_bytes());
        }
        fn int(&mut self, v: i32) {
            self.0.extend_from_slice(&v.to_le_bytes());
        }
        fn f(&mut self, v: f64) {
            self.0.extend_from_slice(&v.to_le_bytes());
        }
        fn bbox(&mut self, pts: impl Iterator<Item = [f64; 3]> + Clone) {
            for d in 0..3 {
                self.f(pts.clone().map(|p| p[d]).fold(f64::INFINITY, f64::min));
            }
            for d in 0..3 {
                self.f(pts.clone().map(|p| p[d]).fold(f64::NEG_INFINITY, f64::max));
            }
        }
    }
    let sets: Vec<(&String, &Vec<[u32; 3]>)> = mesh.face_sets.iter().collect();
    let mut w = Bin(Vec::new());
    w.s("$MeshFormat\n4.1 1 8\n");
    w.int(1);
    w.s("\n$EndMeshFormat\n$PhysicalNames\n");
    w.s(&format!("{}\n", sets.len() + 1));
    for (i, (name, _)) in sets.iter().enumerate() {
        w.s(&format!("2 {} \"{name}\"\n", i + 1));
    }
    w.s("3 1 \"all\"\n$EndPhysicalNames\n$Entities\n");
    for n in [0, 0, sets.len(), 1] {
        w.sz(n);
    }
    for (i, (_, faces)) in sets.iter().enumerate() {
        w.int(i as i32 + 1);
        w.bbox(faces.iter().flatten().map(|&n| mesh.nodes[n as usize]));
        w.sz(1);
        w.int(i as i32 + 1);
        w.sz(0);
    }
    w.int(1);
    w.bbox(mesh.nodes.iter().copied());
    w.sz(1);
    w.int(1);
    w.sz(0);
    let n = mesh.nodes.len();
    w.s("\n$EndEntities\n$Nodes\n");
    for v in [1, n, 1, n] {
        w.sz(v);
    }
    w.int(3);
    w.int(1);
    w.int(0);
    w.sz(n);
    for i in 0..n {
        w.sz(i + 1);
    }
    for p in &mesh.nodes {
        p.iter().for_each(|&c| w.f(c));
    }
    let tris: usize = sets.iter().map(|s| s.1.len()).sum();
    let total = tris + mesh.tets.len();
    w.s("\n$EndNodes\n$Elements\n");
    for v in [sets.len() + 1, total, 1, total] {
        w.sz(v);
    }
    let mut tag = 1;
    for (i, (_, faces)) in sets.iter().enumerate() {
        w.int(2);
        w.int(i as i32 + 1);
        w.int(2);
        w.sz(faces.len());
        for f in faces.iter() {
            w.sz(tag);
            tag += 1;
            f.iter().for_each(|&v| w.sz(v as usize + 1));
        }
    }
    w.int(3);
    w.int(1);
    w.int(4);
    w.sz(mesh.tets.len());
    for t in &mesh.tets {
        w.sz(tag);
        tag += 1;
        t.iter().for_each(|&v| w.sz(v as usize + 1));
    }
    w.s("\n$EndElements\n");
    w.0
}

/// Line indices of an ASCII file's `$Nodes` blocks (tag lines and
/// coordinate lines) and of its `$Elements` element lines; empty where the
/// layout does not parse (a file damaged by an earlier mutation).
struct AsciiLayout {
    node_tags: Vec<Vec<usize>>,
    node_coords: Vec<Vec<usize>>,
    elements: Vec<usize>,
    /// Count lines: section headers and block headers.
    headers: Vec<usize>,
}

fn ascii_layout(lines: &[String]) -> AsciiLayout {
    let mut l = AsciiLayout {
        node_tags: Vec::new(),
        node_coords: Vec::new(),
        elements: Vec::new(),
        headers: Vec::new(),
    };
    let num = |s: &str, k: usize| s.split_whitespace().nth(k)?.parse::<usize>().ok();
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim();
        if t == "$PhysicalNames" || t == "$Entities" {
            l.headers.push(i + 1);
        }
    }
    if let Some(start) = lines.iter().position(|s| s.trim() == "$Nodes") {
        let mut i = start + 1;
        l.headers.push(i);
        let blocks = lines.get(i).and_then(|s| num(s, 0)).unwrap_or(0);
        i += 1;
        for _ in 0..blocks {
            let Some(n) = lines.get(i).and_then(|s| num(s, 3)) else {
                break;
            };
            l.headers.push(i);
            let n = n.min(lines.len());
            l.node_tags.push((i + 1..i + 1 + n).collect());
            l.node_coords.push((i + 1 + n..i + 1 + 2 * n).collect());
            i += 1 + 2 * n;
        }
    }
    if let Some(start) = lines.iter().position(|s| s.trim() == "$Elements") {
        let mut i = start + 1;
        l.headers.push(i);
        let blocks = lines.get(i).and_then(|s| num(s, 0)).unwrap_or(0);
        i += 1;
        for _ in 0..blocks {
            let Some(n) = lines.get(i).and_then(|s| num(s, 3)) else {
                break;
            };
            l.headers.push(i);
            let n = n.min(lines.len());
            l.elements.extend(i + 1..i + 1 + n);
            i += 1 + n;
        }
    }
    let len = lines.len();
    l.node_tags.iter_mut().for_each(|b| b.retain(|&i| i < len));
    l.node_coords
        .iter_mut()
        .for_each(|b| b.retain(|&i| i < len));
    l.elements.retain(|&i| i < len);
    l.headers.retain(|&i| i < len);
    l
}

fn extreme_count(rng: &mut Pcg64) -> String {
    [
        "0",
        "-1",
        "1",
        "4294967296",
        "18446744073709551615",
        "9223372036854775807",
        "1000000000000",
        "1e3",
        "x",
        "",
    ]
    .choose(rng)
    .unwrap()
    .to_string()
}

/// One mutation of an ASCII MSH file, as lines.
fn mutate_ascii_msh(lines: &mut Vec<String>, rng: &mut Pcg64) -> String {
    let l = ascii_layout(lines);
    let tag_of = |s: &str| s.trim().to_string();
    match rng.gen_range(0..10) {
        0 => {
            // Shuffle the tags of a block: the elements then point elsewhere.
            let Some(block) = l.node_tags.choose(rng) else {
                return "no node block".into();
            };
            let mut tags: Vec<String> = block.iter().map(|&i| tag_of(&lines[i])).collect();
            tags.shuffle(rng);
            for (&i, t) in block.iter().zip(tags) {
                lines[i] = t;
            }
            "shuffle node tags".into()
        }
        1 => {
            // Duplicate a tag.
            let all: Vec<usize> = l.node_tags.concat();
            if all.len() < 2 {
                return "no node tags".into();
            }
            let (a, b) = (*all.choose(rng).unwrap(), *all.choose(rng).unwrap());
            lines[b] = lines[a].clone();
            format!("node tag line {} := line {}", b + 1, a + 1)
        }
        2 => {
            // A missing node: its tag and coordinates removed, counts kept
            // or fixed.
            let Some(k) = (0..l.node_tags.len())
                .filter(|&k| !l.node_tags[k].is_empty())
                .collect::<Vec<_>>()
                .choose(rng)
                .copied()
            else {
                return "no node tags".into();
            };
            let j = rng.gen_range(0..l.node_tags[k].len());
            let (t, c) = (l.node_tags[k][j], l.node_coords[k].get(j).copied());
            if let Some(c) = c {
                lines.remove(c);
            }
            lines.remove(t);
            "remove a node".into()
        }
        3 => {
            // An element refers to a tag that is wrong, huge or zero.
            let Some(&e) = l.elements.choose(rng) else {
                return "no elements".into();
            };
            let mut words: Vec<String> = lines[e].split_whitespace().map(String::from).collect();
            if words.len() > 1 {
                let k = rng.gen_range(1..words.len());
                words[k] = ["0", "-1", "999999", "18446744073709551615", "1.5"]
                    .choose(rng)
                    .unwrap()
                    .to_string();
            }
            lines[e] = words.join(" ");
            format!("element line {}: {}", e + 1, lines[e])
        }
        4 => {
            // A count in a section or block header.
            let Some(&h) = l.headers.choose(rng) else {
                return "no headers".into();
            };
            let mut words: Vec<String> = lines[h].split_whitespace().map(String::from).collect();
            if !words.is_empty() {
                let k = rng.gen_range(0..words.len());
                words[k] = extreme_count(rng);
            }
            lines[h] = words.join(" ");
            format!("header line {}: {}", h + 1, lines[h])
        }
        5 => {
            // A coordinate that is not a finite number.
            let all: Vec<usize> = l.node_coords.concat();
            let Some(&c) = all.choose(rng) else {
                return "no coordinates".into();
            };
            let mut words: Vec<String> = lines[c].split_whitespace().map(String::from).collect();
            if !words.is_empty() {
                let k = rng.gen_range(0..words.len());
                words[k] = ["nan", "inf", "-inf", "1e308", "1e-320", "0"]
                    .choose(rng)
                    .unwrap()
                    .to_string();
            }
            lines[c] = words.join(" ");
            format!("coordinate line {}: {}", c + 1, lines[c])
        }
        6 => {
            // Remove or duplicate a whole section.
            let starts: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].starts_with('$') && !lines[i].starts_with("$End"))
                .collect();
            let Some(&s) = starts.choose(rng) else {
                return "no sections".into();
            };
            let end = (s..lines.len())
                .find(|&i| lines[i].starts_with("$End"))
                .unwrap_or(lines.len() - 1);
            let block: Vec<String> = lines[s..=end].to_vec();
            if rng.gen_bool(0.5) {
                lines.drain(s..=end);
                format!("remove section {}", block[0])
            } else {
                let at = rng.gen_range(0..=lines.len());
                lines.splice(at..at, block.iter().cloned());
                format!("duplicate section {}", block[0])
            }
        }
        7 if lines.len() > 1 => {
            let i = rng.gen_range(0..lines.len());
            let j = rng.gen_range(0..lines.len());
            lines.swap(i, j);
            format!("swap lines {} and {}", i + 1, j + 1)
        }
        _ if !lines.is_empty() => {
            let i = rng.gen_range(0..lines.len());
            if rng.gen_bool(0.5) {
                lines.remove(i);
                format!("delete line {}", i + 1)
            } else {
                let copy = lines[i].clone();
                lines.insert(i, copy);
                format!("duplicate line {}", i + 1)
            }
        }
        _ => "empty file".into(),
    }
}

/// Byte-level damage to any MSH file (ASCII or binary).
fn mutate_bytes(b: &mut Vec<u8>, binary: bool, rng: &mut Pcg64) -> String {
    match rng.gen_range(0..if binary { 6 } else { 3 }) {
        0 => {
            let at = rng.gen_range(0..=b.len());
            b.truncate(at);
            format!("truncate at byte {at}")
        }
        1 => {
            let n = rng.gen_range(1..=8);
            for _ in 0..n {
                if !b.is_empty() {
                    let i = rng.gen_range(0..b.len());
                    b[i] ^= 1 << rng.gen_range(0..8);
                }
            }
            format!("flip {n} bit(s)")
        }
        2 => {
            // Delete or repeat a range of bytes.
            if b.is_empty() {
                return "empty".into();
            }
            let i = rng.gen_range(0..b.len());
            let j = (i + rng.gen_range(1..64)).min(b.len());
            if rng.gen_bool(0.5) {
                b.drain(i..j);
                format!("delete bytes {i}..{j}")
            } else {
                let copy = b[i..j].to_vec();
                b.splice(j..j, copy);
                format!("repeat bytes {i}..{j}")
            }
        }
        _ => {
            // Overwrite 8 bytes (a size_t count, a tag, a coordinate) with
            // an extreme value.
            if b.len() < 8 {
                return "too short".into();
            }
            let i = rng.gen_range(0..b.len() - 8) & !3;
            let v: [u8; 8] = *[
                u64::MAX.to_le_bytes(),
                (1u64 << 40).to_le_bytes(),
                0u64.to_le_bytes(),
                f64::NAN.to_le_bytes(),
                (u32::MAX as u64 + 1).to_le_bytes(),
                rng.gen::<u64>().to_le_bytes(),
            ]
            .choose(rng)
            .unwrap();
            b[i..i + 8].copy_from_slice(&v);
            format!("overwrite 8 bytes at {i}")
        }
    }
}

/// A scenario that builds a model from the mesh file `{file}`.
fn mesh_scenario(file: &Path, sets: &[&str]) -> String {
    let mut s = format!(
        r#"
[time]
dt = 1.0
steps = 2
[[materials]]
name = "m"
conductivity = 1.0
specific_heat = 1.0
density = 1.0
[[bodies]]
name = "b"
material = "m"
mesh = {{ kind = "gmsh", file = "{}" }}
"#,
        file.display()
    );
    for set in sets {
        s.push_str(&format!(
            "[[thermal.bc]]\nkind = \"convection\"\nset = \"{set}\"\nh = 1.0\nambient = 0.0\n"
        ));
    }
    s
}

#[test]
fn mutated_meshes_end_in_an_error_or_a_model() {
    let started = Instant::now();
    let mut runner = Runner::new("mesh");
    let dir = root().join("target").join("test-output").join("fuzz");
    let mut box_mesh = fdem::mesh::generate::box_mesh([0.0; 3], [0.2, 0.1, 0.1], 0.05).unwrap();
    fdem::mesh::generate::jitter_interior(&mut box_mesh, 0.01, 3).unwrap();
    let binary = binary_msh(&box_mesh);
    // The binary file as written must read back as the box.
    let bin_path = dir.join("box-binary.msh");
    std::fs::write(&bin_path, &binary).unwrap();
    let back = fdem::mesh::gmsh::read_msh(&bin_path).unwrap();
    assert_eq!(back.tets.len(), box_mesh.tets.len());
    assert_eq!(back.face_sets.len(), 6);
    let bases: Vec<(String, Vec<u8>, bool, Vec<&str>)> = vec![
        (
            "block-irregular.msh".into(),
            std::fs::read(root().join("scenarios/meshes/block-irregular.msh")).unwrap(),
            false,
            vec!["xmin", "ymax"],
        ),
        (
            "nut-144.msh".into(),
            std::fs::read(root().join("scenarios/meshes/nut-144.msh")).unwrap(),
            false,
            vec![],
        ),
        ("box-binary.msh".into(), binary, true, vec!["xmax", "zmin"]),
        (
            "bar-irregular-10.msh".into(),
            std::fs::read(root().join("scenarios/meshes/bar-irregular-10.msh")).unwrap(),
            false,
            vec!["xmin", "xmax"],
        ),
        (
            "bar-irregular-5.msh".into(),
            std::fs::read(root().join("scenarios/meshes/bar-irregular-5.msh")).unwrap(),
            false,
            vec!["ymin"],
        ),
        (
            "c-shape.msh".into(),
            std::fs::read(root().join("scenarios/meshes/c-shape.msh")).unwrap(),
            false,
            vec![],
        ),
    ];
    // Every shipped mesh is among the bases.
    for e in std::fs::read_dir(root().join("scenarios/meshes")).unwrap() {
        let f = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            bases.iter().any(|b| b.0 == f),
            "scenarios/meshes/{f} is not fuzzed: add it to the bases"
        );
    }
    let msh = dir.join("mutated.msh");
    let scen_path = dir.join("mesh.toml");
    for (name, bytes, is_binary, sets) in &bases {
        let text = mesh_scenario(&msh, sets);
        // Unmutated, each base builds a model.
        std::fs::write(&msh, bytes).unwrap();
        check_in_process(&text, &scen_path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
        for number in 0..scaled(CASES_PER_MESH) {
            if !selected(name, number) {
                continue;
            }
            let seed = case_seed(name, number);
            let mut rng = Pcg64::seed_from_u64(seed);
            let mut b = bytes.clone();
            let mut mutations = Vec::new();
            for _ in 0..rng.gen_range(1..=2) {
                if !is_binary && rng.gen_bool(0.7) {
                    let mut lines: Vec<String> = String::from_utf8_lossy(&b)
                        .lines()
                        .map(String::from)
                        .collect();
                    mutations.push(mutate_ascii_msh(&mut lines, &mut rng));
                    b = (lines.join("\n") + "\n").into_bytes();
                } else {
                    mutations.push(mutate_bytes(&mut b, *is_binary, &mut rng));
                }
            }
            std::fs::write(&msh, &b).unwrap();
            let shown = if *is_binary {
                format!("({} bytes of binary MSH; file {})", b.len(), msh.display())
            } else {
                String::from_utf8_lossy(&b).into_owned()
            };
            let case = Case {
                input: name.clone(),
                number,
                seed,
                mutations,
                text: shown,
                sets: Vec::new(),
            };
            runner.run(&case, || check_in_process(&text, &scen_path, &[]));
        }
    }
    assert!(
        runner.cases >= 3 * scaled(CASES_PER_MESH) || std::env::var("FDEM_FUZZ_ONLY").is_ok(),
        "only {} cases",
        runner.cases
    );
    runner.finish("Gmsh meshes (in-process)", started);
}

// ------------------------------------------------------ through the binary

/// Reductions of heavy scenarios before they are mutated (`--set` paths):
/// the in-process check builds the model, the binary also runs it.
fn base_reductions(name: &str, binary: bool) -> Vec<(&'static str, Value)> {
    let mut v = match name {
        "nut-packing-deposit" => vec![(
            "bodies.1.pack.count",
            Value::Integer(if binary { 20 } else { 50 }),
        )],
        // 97,500 jointed tets: a second a case to build.
        "bench-jointed-box" => vec![("bodies.0.mesh.element_size", Value::Float(0.02))],
        "nut-lattice-heatup-20k" => vec![(
            "bodies.1.lattice.count",
            Value::Array(vec![Value::Integer(3); 3]),
        )],
        _ => Vec::new(),
    };
    // 1 M and 0.2 M tets: over or near the fuzz's element limit.
    if let "bench-cube-1m" | "bench-mech-block" = name {
        v.push(("bodies.0.mesh.element_size", Value::Float(0.1)));
    }
    if binary && name == "bench-contact-pack" {
        v.push((
            "bodies.0.lattice.count",
            Value::Array(vec![Value::Integer(2); 3]),
        ));
    }
    v
}

/// The base text of a shipped scenario with its reductions applied.
fn reduced_base(path: &Path, binary: bool) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let reductions = base_reductions(&stem(path), binary);
    if reductions.is_empty() {
        return text;
    }
    let mut doc = Value::Table(toml::from_str(&text).unwrap());
    for (key, value) in reductions {
        let path: Vec<Seg> = key
            .split('.')
            .map(|s| match s.parse() {
                Ok(i) => Seg::Index(i),
                Err(_) => Seg::Key(s.into()),
            })
            .collect();
        *get_mut(&mut doc, &path).unwrap_or_else(|| panic!("{key}")) = value;
    }
    toml::to_string(&doc).unwrap()
}

/// Caps that keep a valid mutated run to a few steps and substeps: at most
/// 2 steps, at most 10 mechanics substeps per step (given explicitly, so
/// the step count does not follow a mutated time step or stiffness), at
/// most 50 particles in a pack and 50 free spheres in a set.
fn cap_run(doc: &mut Value) {
    let num = |v: &Value| match v {
        Value::Integer(n) => Some(*n as f64),
        Value::Float(x) => Some(*x),
        _ => None,
    };
    if let Some(Value::Table(time)) = get_mut(doc, &[Seg::Key("time".into())]) {
        if let Some(Value::Integer(n)) = time.get_mut("steps") {
            *n = (*n).min(2);
        }
        let dt = time.get("dt").and_then(num);
        if let (Some(dt), Some(end)) = (dt, time.get_mut("end_time")) {
            if num(end).is_some_and(|e| dt > 0.0 && e > 2.0 * dt) {
                *end = Value::Float(2.0 * dt);
            }
        }
    }
    if let Some(Value::Table(m)) = get_mut(doc, &[Seg::Key("mechanics".into())]) {
        match m.get_mut("substeps") {
            Some(Value::Integer(n)) => *n = (*n).min(10),
            Some(_) => {}
            None => {
                m.insert("substeps".into(), Value::Integer(10));
            }
        }
    }
    if let Some(Value::Array(bodies)) = get_mut(doc, &[Seg::Key("bodies".into())]) {
        for b in bodies {
            if let Some(Value::Integer(n)) =
                get_mut(b, &[Seg::Key("pack".into()), Seg::Key("count".into())])
            {
                *n = (*n).min(50);
            }
        }
    }
    if let Some(Value::Array(sets)) = get_mut(doc, &[Seg::Key("spheres".into())]) {
        for s in sets {
            if let Some(Value::Integer(n)) = get_mut(s, &[Seg::Key("count".into())]) {
                *n = (*n).min(50);
            }
        }
    }
}

/// Runs `cmd` (in its own process group) with a time limit; `None` if it
/// had to be killed.
fn run_with_limit(
    mut cmd: std::process::Command,
    stdout: &Path,
    stderr: &Path,
) -> Option<std::process::ExitStatus> {
    use std::os::unix::process::CommandExt as _;
    cmd.process_group(0)
        .stdout(std::fs::File::create(stdout).unwrap())
        .stderr(std::fs::File::create(stderr).unwrap())
        .envs(MPI_ENV);
    let mut child = cmd.spawn().expect("cannot start fdem");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return Some(status);
        }
        if start.elapsed() > RUN_LIMIT {
            // The whole group: mpirun and its ranks.
            let _ = std::process::Command::new("kill")
                .args(["-KILL", "--", &format!("-{}", child.id())])
                .status();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// What a run left in `out`: problems, if any. A run refused before its
/// first step leaves nothing (or an empty directory); a run that failed
/// later keeps the steps it completed, readable, and no temporary files.
fn check_outputs(out: &Path, failed: bool) -> Vec<String> {
    let list = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .map(|d| {
                d.flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default()
    };
    let files = list(out);
    let mut problems = Vec::new();
    if failed && files.is_empty() {
        return problems;
    }
    // The series' step files are in `<stem>_steps/`.
    let step_files = files
        .iter()
        .filter(|f| f.ends_with("_steps"))
        .flat_map(|d| {
            list(&out.join(d))
                .into_iter()
                .map(move |f| format!("{d}/{f}"))
        });
    if let Some(t) = files
        .iter()
        .cloned()
        .chain(step_files)
        .find(|f| f.ends_with(".part") || f.ends_with(".tmp"))
    {
        problems.push(format!("temporary file {t} left behind"));
    }
    match files
        .iter()
        .find(|f| f.ends_with(".h5") && !f.ends_with("_checkpoint.h5"))
    {
        None => problems.push(format!("no time series in {files:?}")),
        Some(h5) => match fdem::io::read_times(&out.join(h5)) {
            Ok(t) if !t.is_empty() => {}
            Ok(_) => problems.push(format!("{h5} holds no completed step")),
            Err(e) => problems.push(format!("{h5} is not readable: {e}")),
        },
    }
    problems
}

#[test]
fn mutated_scenarios_through_the_binary() {
    let started = Instant::now();
    let work = out_dir("fuzz-binary");
    std::os::unix::fs::symlink(root().join("scenarios/meshes"), work.join("meshes")).unwrap();
    let scenarios = shipped_scenarios();
    let (mut ok, mut refused, mut later) = (0, 0, 0);
    let mut failures = Vec::new();
    for number in 0..scaled(BINARY_CASES) {
        let path = &scenarios[number % scenarios.len()];
        let name = stem(path);
        let input = format!("binary-{name}");
        if !selected(&input, number) {
            continue;
        }
        let seed = case_seed(&input, number);
        let mut rng = Pcg64::seed_from_u64(seed);
        let base = reduced_base(path, true);
        let m = mutate_scenario(&base, &mut rng, Some(&cap_run));
        let scen = work.join(format!("{number:03}-{name}.toml"));
        std::fs::write(&scen, &m.text).unwrap();
        let out = work.join(format!("out-{number:03}"));
        let ranks = if number % 5 == 4 { 2 } else { 1 };
        let bin = env!("CARGO_BIN_EXE_fdem");
        let mut cmd = if ranks > 1 {
            let mut c = std::process::Command::new("mpirun");
            c.args(["-n", "2", "--oversubscribe", bin]);
            c
        } else {
            std::process::Command::new(bin)
        };
        cmd.arg("run")
            .arg(&scen)
            .arg("--quiet")
            .arg("--output")
            .arg(&out);
        for s in &m.sets {
            cmd.args(["--set", s]);
        }
        let (so, se) = (
            work.join(format!("{number:03}.stdout")),
            work.join(format!("{number:03}.stderr")),
        );
        let status = run_with_limit(cmd, &so, &se);
        let stderr = std::fs::read_to_string(&se).unwrap_or_default();
        let case = Case {
            input: input.clone(),
            number,
            seed,
            mutations: m.mutations,
            text: m.text.clone(),
            sets: m.sets.clone(),
        };
        let mut problems = Vec::new();
        match status.and_then(|s| s.code()) {
            None => problems.push(format!("killed after {RUN_LIMIT:?} or by a signal")),
            Some(0) => {
                ok += 1;
                problems.extend(check_outputs(&out, false));
            }
            Some(1) => {
                let messages = stderr.lines().filter(|l| l.starts_with("error: ")).count();
                if messages != 1 {
                    problems.push(format!("{messages} error messages on stderr"));
                }
                let left = check_outputs(&out, true);
                if std::fs::read_dir(&out).is_ok_and(|mut d| d.next().is_some()) {
                    later += 1;
                } else {
                    refused += 1;
                }
                problems.extend(left);
            }
            Some(c) => problems.push(format!("exit status {c}")),
        }
        if stderr.contains("panicked") {
            problems.push("panic message on stderr".into());
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{problems:?} on {ranks} rank(s) in\n{case}stderr:\n{stderr}"
            ));
        }
    }
    eprintln!(
        "fuzz through the binary: {} runs in {:.1} s: {ok} succeeded, {refused} refused before \
         any output, {later} failed after writing steps; {} failures",
        ok + refused + later,
        started.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of the runs failed; the first:\n{}",
        failures.len(),
        failures[0]
    );
}
