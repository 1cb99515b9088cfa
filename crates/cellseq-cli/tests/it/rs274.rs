//! The judge of issue 25: LinuxCNC's own interpreter (`rs274`, Debian `linuxcnc-uspace`) reads
//! every G-code program in `tests/fixtures/gcode/` (the real programs of `real/` and the small
//! fixtures beside them) and what `cellseq optimize` writes for it — with default options,
//! `--merge-tool-blocks` and `--reversible` — and the two streams of canonical machine calls are
//! replayed into a machine state and compared. This file shares no code with `src/io/gcode`: it
//! runs the built binary and reads only what `rs274` prints.
//!
//! A rewrite passes when
//! - **state-exact**: the multiset of cutting moves (`STRAIGHT_FEED`, `ARC_FEED`), each tagged
//!   with the full machine state it runs in (spindle direction and speed, mist, flood, feed rate
//!   and mode, tool and tool-length offset, units, plane, work and G92 offsets, rotation,
//!   motion-control mode, cutter compensation, …; state the program never set stays *unset*),
//!   equals the original's — as undirected segments and arcs (rotation sign flipped) when
//!   cellseq reports reversed cells or `--reversible` was given, directed otherwise;
//! - the same holds for dwells, M0/M1, tool changes, probing, rigid tapping and messages (with
//!   `--merge-tool-blocks`: the same distinct events, none more often than in the original);
//! - **no new motion**: every rapid of the output moving in XY does so no lower than the lowest
//!   height at which the original rapids in XY, no rapid goes deeper than the original's deepest
//!   rapid, the first motion happens in the original's state at its first motion, and none comes
//!   before the first tool change where the original changes tools before moving;
//! - **never worse**: cellseq's own report has air, lifts and time after ≤ before, and the air
//!   and lifts recomputed here from the canonical calls are not worse either;
//! - and `rs274` reports no error on the output that it does not report on the original.
//!
//! A refused program passes only if the message names the file and a line and says what to do.
//! Without `rs274` the tests print a notice and return, except under `CI=true`, where they fail.
//!
//! `CELLSEQ_CORPUS_FILTER=substring` limits the corpus test to matching files;
//! `CELLSEQ_CORPUS_TABLE=path` writes its per-file Markdown table there
//! (`scripts/gcode_corpus.sh` does both).

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Coordinates are compared on this grid (program units): `rs274` prints four decimals.
const GRID: f64 = 1e-3;
/// Two coordinates closer than this match in the second, tolerant pass.
const TOL: f64 = 2e-3;
static RS274: std::sync::Mutex<()> = std::sync::Mutex::new(());
const RS274_TIMEOUT: Duration = Duration::from_secs(120);
const CELLSEQ_TIMEOUT: Duration = Duration::from_secs(600);

// ---------------------------------------------------------------------------------------------
// Running programs
// ---------------------------------------------------------------------------------------------

/// Whether `rs274` can be run; under `CI=true` its absence is a failure.
fn rs274_or_notice() -> bool {
    let found = Command::new("sh")
        .args(["-c", "command -v rs274"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !found {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "rs274 (Debian linuxcnc-uspace) is not installed, and CI=true: the state-exact \
             check cannot run"
        );
        println!(
            "NOTICE: rs274 not on PATH (apt-get install linuxcnc-uspace): the state-exact \
             real-interpreter check did NOT run"
        );
    }
    found
}

struct Ran {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs a command in `dir` with stdin closed and stdout/stderr sent to files (no pipe can fill
/// up), killing it after `timeout`.
fn run(cmd: &mut Command, dir: &Path, timeout: Duration) -> Result<Ran, String> {
    let out = dir.join("stdout.txt");
    let err = dir.join("stderr.txt");
    let mut child = cmd
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).map_err(|e| e.to_string())?)
        .stderr(std::fs::File::create(&err).map_err(|e| e.to_string())?)
        .spawn()
        .map_err(|e| format!("cannot start {cmd:?}: {e}"))?;
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| e.to_string())? {
            break s;
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("{cmd:?} ran past {timeout:?} and was killed"));
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let read =
        |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
    Ok(Ran {
        code: status.code(),
        stdout: read(&out),
        stderr: read(&err),
    })
}

/// A tool table with tools 1–99, each with its own length offset and diameter, so that a
/// cancelled or different tool-length offset changes the state and cutter compensation works.
fn tool_table() -> String {
    (1..100)
        .map(|t| {
            format!(
                "T{t} P{t} Z{:.3} D{:.3}\n",
                0.5 + 0.1 * t as f64,
                0.1 + 0.01 * t as f64
            )
        })
        .collect()
}

/// The state the operator left the machine in before the program starts: tool 1 loaded with
/// its length offset, work offset G55, spindle on at 1234, mist and flood on, feed 777, path
/// blending `G64 P0.05`. `rs274` prints a call only when a setting changes, so a program that
/// sets something the original never sets (`M9`, `M5`, `S0`, `G54`, `G49`, `G61`, `F…`) shows
/// up as a change of this state. The marker message ends it: the replay takes state from the
/// calls before it but no motion or event.
const OPERATOR: &str = "T1 M6\nG43 H1\nG55\nM3 S1234\nM7\nM8\nF777\nG64 P0.05\n\
                        (MSG,judge: program starts)\n";
const MARKER: &str = "judge: program starts";

/// One canonical call: `NAME(args)`.
#[derive(Clone, Debug)]
struct Call {
    name: String,
    args: String,
}

impl Call {
    fn nums(&self) -> Vec<f64> {
        self.args
            .split(',')
            .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN))
            .collect()
    }
}

/// What `rs274` made of a program: its canonical calls (after the interpreter's own start-up,
/// which ends at the first `ON_RESET`) and its error messages.
struct Canon {
    calls: Vec<Call>,
    errors: Vec<String>,
}

/// Runs `rs274 -n 0 -t tools.tbl -g` on `text` in a fresh directory under `dir` (the
/// interpreter keeps a parameter file in its working directory). `M2` is appended: in continue
/// mode (`-n 0`) a file without a program end makes `rs274` repeat its error forever, and after a
/// program end nothing more is read.
fn rs274(dir: &Path, tag: &str, text: &str) -> Result<Canon, String> {
    let d = dir.join(tag);
    std::fs::create_dir_all(&d).map_err(|e| e.to_string())?;
    std::fs::write(d.join("tools.tbl"), tool_table()).map_err(|e| e.to_string())?;
    std::fs::write(d.join("prog.ngc"), format!("{OPERATOR}{text}\nM2\n"))
        .map_err(|e| e.to_string())?;
    // concurrent rs274 processes disturb each other (seen: one killed by a signal, another
    // missing its tool change), so they run one at a time
    let r = {
        let _one = RS274.lock().unwrap_or_else(|e| e.into_inner());
        run(
            Command::new("rs274").args(["-n", "0", "-t", "tools.tbl", "-g", "prog.ngc"]),
            &d,
            RS274_TIMEOUT,
        )?
    };
    if r.code != Some(0) {
        return Err(format!("rs274 exited with {:?}: {}", r.code, r.stderr));
    }
    let mut calls = Vec::new();
    let mut started = false;
    for line in r.stdout.lines() {
        // "   12 N..... NAME(args)" or "   12 N0040  NAME(args)"
        let mut it = line.trim_start().splitn(3, ' ');
        let (Some(_), Some(_), Some(rest)) = (it.next(), it.next(), it.next()) else {
            continue;
        };
        let rest = rest.trim();
        let (Some(a), Some(b)) = (rest.find('('), rest.rfind(')')) else {
            continue;
        };
        let call = Call {
            name: rest[..a].to_string(),
            args: rest[a + 1..b].trim().to_string(),
        };
        if !started {
            started = call.name == "ON_RESET";
            continue;
        }
        calls.push(call);
    }
    // stderr: "executing", then pairs of (message, offending line)
    let errs: Vec<&str> = r.stderr.lines().filter(|l| *l != "executing").collect();
    let errors = errs.chunks(2).map(|c| c[0].to_string()).collect();
    Ok(Canon { calls, errors })
}

// ---------------------------------------------------------------------------------------------
// Replay: canonical calls -> state-tagged moves and events
// ---------------------------------------------------------------------------------------------

/// The machine state: every field the program has set, by name; a field the program never set
/// is absent (it belongs to the operator).
type State = BTreeMap<&'static str, String>;

#[derive(Clone, Debug)]
struct Move {
    arc: bool,
    /// start then end, x y z a b c each
    ends: [[f64; 6]; 2],
    /// arc centre (x, y, z; the axis coordinate is 0) and rotation (signed turns)
    centre: [f64; 3],
    rotation: i64,
    state: State,
}

#[derive(Clone, Debug)]
struct Event {
    what: String,
    at: [f64; 6],
    state: State,
}

#[derive(Default)]
struct Replay {
    feeds: Vec<Move>,
    /// rapids (start, end)
    traverses: Vec<[[f64; 6]; 2]>,
    events: Vec<Event>,
    /// state at the first motion of any kind
    first_motion_state: Option<State>,
    /// index (in calls) of the first motion and the first tool change
    first_motion: Option<usize>,
    first_tool_change: Option<usize>,
}

/// Fields set by calls that only change state: call name -> state field.
fn state_field(name: &str) -> Option<&'static str> {
    Some(match name {
        "USE_LENGTH_UNITS" => "units",
        "SELECT_PLANE" => "plane",
        "SET_G5X_OFFSET" => "work offset",
        "SET_G92_OFFSET" => "G92 offset",
        "SET_XY_ROTATION" => "rotation",
        "SET_FEED_REFERENCE" => "feed reference",
        "SET_FEED_RATE" => "feed rate",
        "SET_FEED_MODE" => "feed mode",
        "SET_SPINDLE_SPEED" => "spindle speed",
        "SET_SPINDLE_MODE" => "spindle mode",
        "USE_TOOL_LENGTH_OFFSET" => "tool length offset",
        "SET_CUTTER_RADIUS_COMPENSATION" => "cutter radius",
        "SET_MOTION_CONTROL_MODE" => "motion control",
        "SET_NAIVECAM_TOLERANCE" => "naive-CAM tolerance",
        "SET_TRAVERSE_RATE" => "traverse rate",
        "ENABLE_FEED_OVERRIDE" | "DISABLE_FEED_OVERRIDE" => "feed override",
        "ENABLE_SPEED_OVERRIDE" | "DISABLE_SPEED_OVERRIDE" => "speed override",
        "ENABLE_ADAPTIVE_FEED" | "DISABLE_ADAPTIVE_FEED" => "adaptive feed",
        "ENABLE_FEED_HOLD" | "DISABLE_FEED_HOLD" => "feed hold",
        _ => return None,
    })
}

/// Canonical position (x y z a b c) of a straight move's arguments.
fn pos6(n: &[f64]) -> [f64; 6] {
    let mut p = [0.0; 6];
    for (i, v) in n.iter().take(6).enumerate() {
        p[i] = *v;
    }
    p
}

fn replay(calls: &[Call]) -> Replay {
    let mut r = Replay::default();
    let mut s = State::new();
    let mut pos = [0.0f64; 6];
    let mut started = false;
    for (i, c) in calls.iter().enumerate() {
        let name = c.name.as_str();
        if !started {
            // the operator's preamble: its state counts, its motion and events do not
            if name == "MESSAGE" && c.args.contains(MARKER) {
                started = true;
            } else if let Some(f) = state_field(name) {
                s.insert(f, c.args.clone());
            } else {
                match name {
                    "START_SPINDLE_CLOCKWISE" => drop(s.insert("spindle", "clockwise".into())),
                    "MIST_ON" => drop(s.insert("mist", "ON".into())),
                    "FLOOD_ON" => drop(s.insert("flood", "ON".into())),
                    "CHANGE_TOOL" => drop(s.insert("tool", c.args.clone())),
                    _ => {}
                }
            }
            continue;
        }
        let is_motion = matches!(
            name,
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" | "ARC_FEED" | "STRAIGHT_PROBE" | "RIGID_TAP"
        );
        if is_motion && r.first_motion.is_none() {
            r.first_motion = Some(i);
            r.first_motion_state = Some(s.clone());
        }
        if let Some(f) = state_field(name) {
            s.insert(f, c.args.clone());
            continue;
        }
        match name {
            "COMMENT" | "ON_RESET" | "START_CHANGE" | "SELECT_TOOL" | "TURN_PROBE_ON"
            | "TURN_PROBE_OFF" => {}
            "START_SPINDLE_CLOCKWISE" => {
                s.insert("spindle", "clockwise".into());
            }
            "START_SPINDLE_COUNTERCLOCKWISE" => {
                s.insert("spindle", "counterclockwise".into());
            }
            "STOP_SPINDLE_TURNING" => {
                s.insert("spindle", "off".into());
            }
            "MIST_ON" | "MIST_OFF" => {
                s.insert("mist", name[5..].to_string());
            }
            "FLOOD_ON" | "FLOOD_OFF" => {
                s.insert("flood", name[6..].to_string());
            }
            "START_CUTTER_RADIUS_COMPENSATION" => {
                s.insert("cutter compensation", c.args.clone());
            }
            "STOP_CUTTER_RADIUS_COMPENSATION" => {
                s.insert("cutter compensation", "off".into());
            }
            "START_SPEED_FEED_SYNCH" => {
                s.insert("spindle sync", c.args.clone());
            }
            "STOP_SPEED_FEED_SYNCH" => {
                s.insert("spindle sync", "off".into());
            }
            "STRAIGHT_TRAVERSE" => {
                let e = pos6(&c.nums());
                r.traverses.push([pos, e]);
                pos = e;
            }
            "STRAIGHT_FEED" => {
                let e = pos6(&c.nums());
                // a feed move to where the tool already is moves nothing and cuts nothing (CAM
                // posts write such lines between cells); it is not a cutting move
                if (0..6).all(|k| (e[k] - pos[k]).abs() < 1e-9) {
                    continue;
                }
                r.feeds.push(Move {
                    arc: false,
                    ends: [pos, e],
                    centre: [0.0; 3],
                    rotation: 0,
                    state: s.clone(),
                });
                pos = e;
            }
            "ARC_FEED" => {
                let n = c.nums();
                let mut e = pos;
                let mut centre = [0.0; 3];
                // ARC_FEED(first_end, second_end, first_centre, second_centre, rotation,
                // axis_end, a, b, c, ...); first/second/axis = XY/Z, ZX/Y or YZ/X by plane
                let (f, sec, ax) = match s.get("plane").map(String::as_str) {
                    Some("CANON_PLANE_XZ") => (2, 0, 1),
                    Some("CANON_PLANE_YZ") => (1, 2, 0),
                    _ => (0, 1, 2),
                };
                e[f] = n[0];
                e[sec] = n[1];
                e[ax] = n[5];
                centre[f] = n[2];
                centre[sec] = n[3];
                for (k, v) in n.iter().skip(6).take(3).enumerate() {
                    e[3 + k] = *v;
                }
                r.feeds.push(Move {
                    arc: true,
                    ends: [pos, e],
                    centre,
                    rotation: n[4] as i64,
                    state: s.clone(),
                });
                pos = e;
            }
            _ => {
                // every other call is an event: dwell, M0/M1, tool change, probe, tap, message,
                // program end, and anything this judge does not know (never silently dropped)
                if name == "CHANGE_TOOL" {
                    s.insert("tool", c.args.clone());
                    r.first_tool_change.get_or_insert(i);
                }
                // where a probe or tap happens matters; a dwell's height matters (at the
                // bottom of a hole, or at the link height between cells), but its X/Y between
                // cells is the position of the link, which a reorder legitimately changes; where
                // a stop, tool change or program end happens is the link's business
                let at = match name {
                    "STRAIGHT_PROBE" | "RIGID_TAP" => pos6(&c.nums()),
                    "DWELL" => [0.0, 0.0, pos[2], pos[3], pos[4], pos[5]],
                    _ => [0.0; 6],
                };
                r.events.push(Event {
                    what: format!("{name}({})", c.args),
                    at,
                    state: s.clone(),
                });
                if name == "STRAIGHT_PROBE" {
                    pos = at;
                }
            }
        }
    }
    r
}

// ---------------------------------------------------------------------------------------------
// Comparison
// ---------------------------------------------------------------------------------------------

fn q(v: f64) -> i64 {
    (v / GRID).round() as i64
}

fn q6(p: &[f64; 6]) -> [i64; 6] {
    p.map(q)
}

/// The move in comparable form: undirected (lexicographically smaller end first, rotation
/// negated when swapped; a closed arc counts as counter-clockwise) or directed.
fn normal(m: &Move, undirected: bool) -> Move {
    let mut m = m.clone();
    if undirected {
        let (a, b) = (q6(&m.ends[0]), q6(&m.ends[1]));
        if a > b {
            m.ends.swap(0, 1);
            m.rotation = -m.rotation;
        } else if a == b {
            m.rotation = m.rotation.abs();
        }
    }
    m
}

type MoveKey = (State, bool, [i64; 6], [i64; 6], [i64; 3], i64);

fn move_key(m: &Move) -> MoveKey {
    (
        m.state.clone(),
        m.arc,
        q6(&m.ends[0]),
        q6(&m.ends[1]),
        m.centre.map(q),
        m.rotation,
    )
}

fn near(a: &Move, b: &Move) -> bool {
    let close = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(u, v)| (u - v).abs() <= TOL);
    a.arc == b.arc
        && a.rotation == b.rotation
        && a.state == b.state
        && close(&a.ends[0], &b.ends[0])
        && close(&a.ends[1], &b.ends[1])
        && close(&a.centre, &b.centre)
}

/// Where two states differ, as "field: original -> output".
fn state_diff(a: &State, b: &State) -> String {
    let mut d = Vec::new();
    for k in a.keys().chain(b.keys().filter(|k| !a.contains_key(*k))) {
        let (x, y) = (a.get(k), b.get(k));
        if x != y {
            let show = |v: Option<&String>| v.cloned().unwrap_or_else(|| "unset".into());
            d.push(format!("{k}: {} -> {}", show(x), show(y)));
        }
    }
    d.join("; ")
}

/// Compares the cutting moves as multisets; returns the problems found.
fn compare_feeds(a: &[Move], b: &[Move], undirected: bool) -> Vec<String> {
    let a: Vec<Move> = a.iter().map(|m| normal(m, undirected)).collect();
    let b: Vec<Move> = b.iter().map(|m| normal(m, undirected)).collect();
    let mut count: HashMap<MoveKey, (Vec<usize>, Vec<usize>)> = HashMap::new();
    for (i, m) in a.iter().enumerate() {
        count.entry(move_key(m)).or_default().0.push(i);
    }
    for (i, m) in b.iter().enumerate() {
        count.entry(move_key(m)).or_default().1.push(i);
    }
    let (mut only_a, mut only_b) = (Vec::new(), Vec::new());
    for (_, (x, y)) in count {
        let k = x.len().min(y.len());
        only_a.extend_from_slice(&x[k..]);
        only_b.extend_from_slice(&y[k..]);
    }
    // tolerant pass for values that fell on both sides of a grid line
    if only_a.len() + only_b.len() <= 20_000 {
        only_b.retain(|&j| {
            if let Some(p) = only_a.iter().position(|&i| near(&a[i], &b[j])) {
                only_a.swap_remove(p);
                false
            } else {
                true
            }
        });
    }
    let mut problems = Vec::new();
    if !only_a.is_empty() || !only_b.is_empty() {
        problems.push(format!(
            "cutting moves differ: {} of the original's {} have no match in the output, {} of \
             the output's {} none in the original",
            only_a.len(),
            a.len(),
            only_b.len(),
            b.len()
        ));
        only_a.sort_unstable();
        only_b.sort_unstable();
        if let (Some(&i), Some(&j)) = (only_a.first(), only_b.first()) {
            let same_geometry = |x: &Move, y: &Move| {
                let mut y = y.clone();
                y.state = x.state.clone();
                near(x, &y)
            };
            // name the state difference of a move whose geometry matches
            if let Some(&j2) = only_b.iter().find(|&&j| same_geometry(&a[i], &b[j])) {
                problems.push(format!(
                    "a cut runs in another state: {}",
                    state_diff(&a[i].state, &b[j2].state)
                ));
            } else {
                problems.push(format!(
                    "first unmatched: original {:?} -> {:?}; output {:?} -> {:?} ({})",
                    &a[i].ends[0][..3],
                    &a[i].ends[1][..3],
                    &b[j].ends[0][..3],
                    &b[j].ends[1][..3],
                    state_diff(&a[i].state, &b[j].state)
                ));
            }
        }
    }
    problems
}

/// Compares the events (dwell, stops, tool changes, probes, …) with their state and position.
fn compare_events(a: &[Event], b: &[Event], merged: bool) -> Vec<String> {
    type Key = (String, [i64; 6], State);
    let key = |e: &Event| -> Key { (e.what.clone(), q6(&e.at), e.state.clone()) };
    let mut count: BTreeMap<Key, (usize, usize)> = BTreeMap::new();
    for e in a {
        count.entry(key(e)).or_default().0 += 1;
    }
    for e in b {
        count.entry(key(e)).or_default().1 += 1;
    }
    let mut problems = Vec::new();
    for ((what, at, state), (x, y)) in &count {
        let bad = if merged {
            (*x == 0) != (*y == 0) || y > x
        } else {
            x != y
        };
        if bad {
            problems.push(format!(
                "event {what} at {:?} ({} state fields): {x} in the original, {y} in the output",
                &at[..3].iter().map(|v| *v as f64 * GRID).collect::<Vec<_>>(),
                state.len()
            ));
        }
    }
    if problems.len() > 3 {
        let n = problems.len();
        problems.truncate(3);
        problems.push(format!("… {n} event differences in all"));
    }
    problems
}

/// Air (rapid length) and lifts (rapid runs between cuts that go up) from the canonical calls.
fn canon_air_lifts(calls: &[Call]) -> (f64, usize) {
    let (mut air, mut lifts) = (0.0, 0usize);
    let mut pos = [0.0f64; 3];
    let mut rising = false;
    let mut in_run = false;
    let mut cut = false;
    for c in calls {
        match c.name.as_str() {
            "STRAIGHT_TRAVERSE" => {
                let n = c.nums();
                let e = [n[0], n[1], n[2]];
                air +=
                    ((e[0] - pos[0]).powi(2) + (e[1] - pos[1]).powi(2) + (e[2] - pos[2]).powi(2))
                        .sqrt();
                rising |= e[2] > pos[2] + GRID;
                in_run = true;
                pos = e;
            }
            "STRAIGHT_FEED" | "ARC_FEED" | "STRAIGHT_PROBE" => {
                if cut && in_run && rising {
                    lifts += 1;
                }
                cut = true;
                in_run = false;
                rising = false;
                let n = c.nums();
                pos = if c.name == "ARC_FEED" {
                    // only z matters for lifts and the xy end for the next air length; plane
                    // changes are rare enough that XY is taken as is
                    [n[0], n[1], n[5]]
                } else {
                    [n[0], n[1], n[2]]
                };
            }
            _ => {}
        }
    }
    (air, lifts)
}

/// The "no new motion" rules; see the module documentation.
fn check_motion(orig: &Replay, out: &Replay) -> Vec<String> {
    let mut problems = Vec::new();
    let moves_xy =
        |t: &[[f64; 6]; 2]| (t[0][0] - t[1][0]).abs() > GRID || (t[0][1] - t[1][1]).abs() > GRID;
    let lowest_xy = orig
        .traverses
        .iter()
        .filter(|t| moves_xy(t))
        .map(|t| t[0][2].min(t[1][2]))
        .fold(f64::INFINITY, f64::min);
    let clear = if lowest_xy.is_finite() {
        lowest_xy
    } else {
        // no sideways rapid at all: the highest point the original reaches
        orig.feeds
            .iter()
            .flat_map(|m| [m.ends[0][2], m.ends[1][2]])
            .chain(orig.traverses.iter().flat_map(|t| [t[0][2], t[1][2]]))
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let deepest = orig
        .traverses
        .iter()
        .map(|t| t[1][2])
        .fold(f64::INFINITY, f64::min);
    let low: Vec<_> = out
        .traverses
        .iter()
        .filter(|t| moves_xy(t) && t[0][2].min(t[1][2]) < clear - TOL)
        .collect();
    if let Some(t) = low.first() {
        problems.push(format!(
            "{} rapid(s) move sideways below the original's clearance Z {clear:.4}, e.g. {:?} -> {:?}",
            low.len(),
            &t[0][..3],
            &t[1][..3]
        ));
    }
    let deep = out
        .traverses
        .iter()
        .filter(|t| t[1][2] < deepest - TOL)
        .count();
    if deep > 0 {
        problems.push(format!(
            "{deep} rapid(s) go below the original's deepest rapid Z {deepest:.4}"
        ));
    }
    if let (Some(a), Some(b)) = (&orig.first_motion_state, &out.first_motion_state)
        && a != b
    {
        problems.push(format!(
            "the first motion runs in another state: {}",
            state_diff(a, b)
        ));
    }
    if let (Some(om), Some(ot)) = (orig.first_motion, orig.first_tool_change)
        && ot < om
        && let Some(m) = out.first_motion
        && out.first_tool_change.is_none_or(|t| m < t)
    {
        problems.push("the output moves before its first tool change".into());
    }
    problems
}

// ---------------------------------------------------------------------------------------------
// Judging one program
// ---------------------------------------------------------------------------------------------

/// Figures from cellseq's JSON report.
#[derive(Clone, Copy, Default)]
struct Figures {
    air: f64,
    lifts: f64,
    time: f64,
}

enum Outcome {
    /// refused by cellseq; `ok` when the message names the file, a line and what to do
    Refused { msg: String, ok: bool },
    /// rewritten and judged
    Judged {
        problems: Vec<String>,
        before: Figures,
        after: Figures,
        canon_air: (f64, f64),
        canon_lifts: (usize, usize),
        cuts: usize,
        reversed: usize,
    },
    /// the judge itself could not run (rs274 failed, cellseq hung, …)
    Broken(String),
}

impl Outcome {
    fn passed(&self) -> bool {
        match self {
            Outcome::Refused { ok, .. } => *ok,
            Outcome::Judged { problems, .. } => problems.is_empty(),
            Outcome::Broken(_) => false,
        }
    }
}

/// Whether a refusal message names the file, a line and what to do (the advice is recognised
/// by its usual words; the table prints the message for a human to read as well).
fn refusal_ok(msg: &str, file: &str) -> bool {
    let names_file = msg.contains(file);
    let after = msg.split(file).nth(1).unwrap_or("");
    let digit_after = |s: &str| s.starts_with(|c: char| c.is_ascii_digit());
    let has_line = (after.starts_with(':') && digit_after(&after[1..]))
        || msg.split("line ").skip(1).any(digit_after);
    let lower = msg.to_lowercase();
    let advice = [
        "use ", "remove", "expand", "replace", "instead", "convert", "try ", "--",
    ]
    .iter()
    .any(|w| lower.contains(w));
    names_file && has_line && advice
}

fn figures(v: &serde_json::Value) -> Figures {
    let f = |k: &str| {
        v.get(k)
            .and_then(serde_json::Value::as_f64)
            .unwrap_or(f64::NAN)
    };
    Figures {
        air: f("air_length"),
        lifts: f("lifts"),
        time: f("est_time_s"),
    }
}

fn worse(after: f64, before: f64) -> bool {
    after.is_nan() || after > before * (1.0 + 1e-9) + 1e-9
}

/// Runs cellseq with `flags` on `path` and judges the result against the original.
fn judge(path: &Path, flags: &[&str], work: &Path) -> Outcome {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let original = match std::fs::read(path) {
        Ok(b) => String::from_utf8_lossy(&b).into_owned(),
        Err(e) => return Outcome::Broken(format!("cannot read {name}: {e}")),
    };
    let _ = std::fs::create_dir_all(work);
    let out_path = work.join(format!("out_{name}"));
    let ran = run(
        crate::common::cellseq()
            .arg("optimize")
            .arg(path)
            .arg("-o")
            .arg(&out_path)
            .arg("--json")
            .args(flags),
        work,
        CELLSEQ_TIMEOUT,
    );
    let ran = match ran {
        Ok(r) => r,
        Err(e) => return Outcome::Broken(e),
    };
    if ran.code != Some(0) {
        let msg = ran.stderr.trim().to_string();
        if ran.code.is_none() || msg.contains("panicked") {
            return Outcome::Broken(format!("cellseq crashed: {msg}"));
        }
        let ok = refusal_ok(&msg, &path.to_string_lossy());
        return Outcome::Refused { msg, ok };
    }
    let report: serde_json::Value = match serde_json::from_str(&ran.stdout) {
        Ok(v) => v,
        Err(e) => return Outcome::Broken(format!("cellseq --json printed no JSON ({e})")),
    };
    let output = match std::fs::read(&out_path) {
        Ok(b) => String::from_utf8_lossy(&b).into_owned(),
        Err(e) => return Outcome::Broken(format!("cellseq wrote no output file: {e}")),
    };
    let (a, b) = match (rs274(work, "orig", &original), rs274(work, "out", &output)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => return Outcome::Broken(e),
    };
    let reversed = report
        .get("reversed_cells")
        .and_then(serde_json::Value::as_u64)
        .unwrap_or(0) as usize;
    let undirected = reversed > 0 || flags.contains(&"--reversible");
    let merged = flags.contains(&"--merge-tool-blocks");
    let (ra, rb) = (replay(&a.calls), replay(&b.calls));
    let mut problems = Vec::new();
    let new_errors: Vec<&String> = b.errors.iter().filter(|e| !a.errors.contains(e)).collect();
    if let Some(e) = new_errors.first() {
        problems.push(format!(
            "rs274 reports {} error(s) on the output that it does not on the original, e.g. {e}",
            new_errors.len()
        ));
    }
    if ra.feeds.is_empty() {
        problems.push("rs274 reads no cutting move in the original".into());
    }
    problems.extend(compare_feeds(&ra.feeds, &rb.feeds, undirected));
    problems.extend(compare_events(&ra.events, &rb.events, merged));
    problems.extend(check_motion(&ra, &rb));
    let before = figures(&report["before"]);
    let after = figures(&report["after"]);
    for (what, x, y) in [
        ("air", after.air, before.air),
        ("lifts", after.lifts, before.lifts),
        ("time", after.time, before.time),
    ] {
        if worse(x, y) {
            problems.push(format!("cellseq's report: {what} worse, {y} -> {x}"));
        }
    }
    let ca = (canon_air_lifts(&a.calls), canon_air_lifts(&b.calls));
    if ca.1.0 > ca.0.0 * (1.0 + 1e-6) + 1e-3 {
        problems.push(format!(
            "air recomputed from rs274: worse, {:.3} -> {:.3}",
            ca.0.0, ca.1.0
        ));
    }
    if ca.1.1 > ca.0.1 {
        problems.push(format!(
            "lifts recomputed from rs274: worse, {} -> {}",
            ca.0.1, ca.1.1
        ));
    }
    Outcome::Judged {
        problems,
        before,
        after,
        canon_air: (ca.0.0, ca.1.0),
        canon_lifts: (ca.0.1, ca.1.1),
        cuts: ra.feeds.len(),
        reversed,
    }
}

// ---------------------------------------------------------------------------------------------
// The corpus
// ---------------------------------------------------------------------------------------------

fn fixtures() -> PathBuf {
    crate::common::fixture_path("gcode")
}

/// Every G-code program under `tests/fixtures/gcode/` (and `real/`), sorted.
fn corpus() -> Vec<PathBuf> {
    let exts = ["ngc", "nc", "gcode", "tap", "gco", "cnc", "g"];
    let mut v = Vec::new();
    for d in [fixtures().join("real"), fixtures()] {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_file()
                && p.extension()
                    .and_then(|x| x.to_str())
                    .is_some_and(|x| exts.contains(&x))
            {
                v.push(p);
            }
        }
    }
    v.sort();
    v
}

const RUNS: [(&str, &[&str]); 3] = [
    ("default", &[]),
    ("merge", &["--merge-tool-blocks"]),
    ("reversible", &["--reversible"]),
];

fn rel(p: &Path) -> String {
    p.strip_prefix(fixtures())
        .unwrap_or(p)
        .to_string_lossy()
        .into_owned()
}

fn row(file: &str, run: &str, o: &Outcome) -> String {
    let cell = |s: &str| s.replace('|', "\\|").replace('\n', " ");
    match o {
        Outcome::Refused { msg, ok } => format!(
            "| {file} | {run} | {} | | | | {} |",
            if *ok {
                "refused (message ok)"
            } else {
                "**refused, message lacks line or advice**"
            },
            cell(&msg.chars().take(160).collect::<String>())
        ),
        Outcome::Broken(e) => format!("| {file} | {run} | **judge failed** | | | | {} |", cell(e)),
        Outcome::Judged {
            problems,
            before,
            after,
            canon_air,
            canon_lifts,
            cuts,
            reversed,
        } => format!(
            "| {file} | {run} | {} | {:.1} → {:.1} (rs274 {:.1} → {:.1}) | {} → {} (rs274 {} → {}) | {:.1} → {:.1} | {} cuts, {} reversed{}{} |",
            if problems.is_empty() { "yes" } else { "**no**" },
            before.air,
            after.air,
            canon_air.0,
            canon_air.1,
            before.lifts,
            after.lifts,
            canon_lifts.0,
            canon_lifts.1,
            before.time,
            after.time,
            cuts,
            reversed,
            if problems.is_empty() { "" } else { "; " },
            cell(
                &problems
                    .iter()
                    .take(3)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join("; ")
            )
        ),
    }
}

/// Every program of the corpus, rewritten by cellseq three ways, judged by rs274.
#[test]
fn rs274_corpus_state_exact() {
    if !rs274_or_notice() {
        return;
    }
    let filter = std::env::var("CELLSEQ_CORPUS_FILTER").unwrap_or_default();
    let files: Vec<PathBuf> = corpus()
        .into_iter()
        .filter(|p| rel(p).contains(&filter))
        .collect();
    assert!(!files.is_empty(), "no corpus file matches {filter:?}");
    let tmp = tempfile::tempdir().unwrap();
    let jobs: Vec<(usize, &PathBuf, usize)> = files
        .iter()
        .enumerate()
        .flat_map(|(i, f)| (0..RUNS.len()).map(move |r| (i, f, r)))
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|sc| {
        for _ in 0..2 {
            sc.spawn(|| {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&(i, f, r)) = jobs.get(k) else { break };
                    let work = tmp.path().join(format!("{i}_{r}"));
                    let o = judge(f, RUNS[r].1, &work);
                    let _ = std::fs::remove_dir_all(&work);
                    results.lock().unwrap().push((i, r, o));
                }
            });
        }
    });
    let mut results = results.into_inner().unwrap();
    results.sort_by_key(|(i, r, _)| (*i, *r));
    let mut table = vec![
        "| file | options | state-exact | air before → after (mm) | lifts | time (s) | notes |"
            .to_string(),
        "|---|---|---|---|---|---|---|".to_string(),
    ];
    let mut failed = Vec::new();
    for (i, r, o) in &results {
        let f = rel(&files[*i]);
        table.push(row(&f, RUNS[*r].0, o));
        if !o.passed() {
            failed.push(format!("{f} ({})", RUNS[*r].0));
        }
    }
    let passed = results.len() - failed.len();
    table.push(String::new());
    table.push(format!(
        "{passed} of {} runs pass ({} files × {} option sets).",
        results.len(),
        files.len(),
        RUNS.len()
    ));
    let table = table.join("\n");
    println!("{table}");
    if let Ok(p) = std::env::var("CELLSEQ_CORPUS_TABLE") {
        std::fs::write(&p, format!("{table}\n")).unwrap();
    }
    assert!(
        failed.is_empty(),
        "{} of {} runs are not machine-safe (table above): {}",
        failed.len(),
        results.len(),
        failed.join(", ")
    );
}

// ---------------------------------------------------------------------------------------------
// The judge judged: it must see what it is meant to see
// ---------------------------------------------------------------------------------------------

fn replay_text(dir: &Path, tag: &str, text: &str) -> (Replay, Canon) {
    let c = rs274(dir, tag, text).unwrap();
    (replay(&c.calls), c)
}

const PART: &str = "G21 G90\nG0 Z5\nM3 S1000\nG0 X0 Y0\nG1 Z-1 F100\nG1 X10 F300\n\
                    G2 X20 Y0 I5 J0\nG0 Z5\nG0 X30 Y0\nG1 Z-1 F100\nG1 X40 F300\nG0 Z5\nM5\nM2\n";

fn verdict(a: &str, b: &str, undirected: bool) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let (ra, _) = replay_text(dir.path(), "a", a);
    let (rb, _) = replay_text(dir.path(), "b", b);
    let mut p = compare_feeds(&ra.feeds, &rb.feeds, undirected);
    p.extend(compare_events(&ra.events, &rb.events, false));
    p.extend(check_motion(&ra, &rb));
    p
}

#[test]
fn judge_accepts_the_same_program_and_a_reordered_one() {
    if !rs274_or_notice() {
        return;
    }
    assert_eq!(verdict(PART, PART, false), Vec::<String>::new());
    // the two cells swapped, each in its own state: the same cuts
    let swapped = "G21 G90\nG0 Z5\nM3 S1000\nG0 X30 Y0\nG1 Z-1 F100\nG1 X40 F300\nG0 Z5\n\
                   G0 X0 Y0\nG1 Z-1 F100\nG1 X10 F300\nG2 X20 Y0 I5 J0\nG0 Z5\nM5\nM2\n";
    assert_eq!(verdict(PART, swapped, false), Vec::<String>::new());
}

#[test]
fn judge_sees_state_the_original_never_set() {
    if !rs274_or_notice() {
        return;
    }
    // coolant switched off, a work offset and a length-offset cancel the original never wrote
    for extra in ["M9\n", "G54\n", "G49\n", "G61\n"] {
        let changed = PART.replacen("M3 S1000\n", &format!("M3 S1000\n{extra}"), 1);
        let p = verdict(PART, &changed, false);
        assert!(
            p.iter().any(|s| s.contains("state")),
            "{extra:?} not seen: {p:?}"
        );
    }
}

#[test]
fn judge_sees_spindle_feed_and_direction_changes() {
    if !rs274_or_notice() {
        return;
    }
    let cases = [
        PART.replacen("G1 X40 F300", "G1 X40 F310", 1),
        PART.replacen("G0 X30 Y0\n", "M5\nG0 X30 Y0\n", 1),
        PART.replacen("M3 S1000", "M3 S0", 1),
        PART.replacen("G2 X20 Y0 I5 J0", "G3 X20 Y0 I5 J0", 1),
    ];
    for c in &cases {
        assert!(!verdict(PART, c, false).is_empty(), "not seen:\n{c}");
    }
    // cells cut backwards (a line, and an arc with G2 -> G3 and its centre offset recomputed):
    // different when directed, the same when reversal is allowed
    let laser = "G21 G90\nM3 S500\nG0 X0 Y0\nG1 X10 F300\nG2 X20 Y0 I5 J0\nG0 X30 Y0\n\
                 G1 X40 F300\nM5\nM2\n";
    let back = "G21 G90\nM3 S500\nG0 X40 Y0\nG1 X30 F300\nG0 X20 Y0\nG3 X10 Y0 I-5 J0\n\
                G1 X0 F300\nM5\nM2\n";
    assert!(!verdict(laser, back, false).is_empty());
    assert_eq!(verdict(laser, back, true), Vec::<String>::new());
}

#[test]
fn judge_sees_new_motion() {
    if !rs274_or_notice() {
        return;
    }
    // a sideways rapid at Z0 before the program's own moves, and a rapid plunge
    let early = PART.replacen("G0 Z5\n", "G0 X3 Y3 Z0\nG0 Z5\n", 1);
    assert!(
        verdict(PART, &early, false)
            .iter()
            .any(|s| s.contains("clearance"))
    );
    let plunge = PART.replacen("G0 X30 Y0\n", "G0 X30 Y0\nG0 Z-0.5\nG0 Z5\n", 1);
    assert!(
        verdict(PART, &plunge, false)
            .iter()
            .any(|s| s.contains("deepest"))
    );
    // a tool change moved after the first motion
    let tc = "G21 G90\nT1 M6\nG0 Z5\nM3 S1000\nG0 X0 Y0\nG1 Z-1 F100\nG1 X10 F300\nG0 Z5\nM2\n";
    let late = "G21 G90\nG0 Z5\nT1 M6\nM3 S1000\nG0 X0 Y0\nG1 Z-1 F100\nG1 X10 F300\nG0 Z5\nM2\n";
    assert!(
        verdict(tc, late, false)
            .iter()
            .any(|s| s.contains("tool change") || s.contains("state"))
    );
}

#[test]
fn judge_sees_events_and_refusal_messages() {
    if !rs274_or_notice() {
        return;
    }
    let dwell = PART.replacen("G1 X10 F300\n", "G1 X10 F300\nG4 P1\n", 1);
    assert!(
        verdict(PART, &dwell, false)
            .iter()
            .any(|s| s.contains("DWELL"))
    );
    let stop = PART.replacen("G0 X30 Y0\n", "M0\nG0 X30 Y0\n", 1);
    assert!(
        verdict(PART, &stop, false)
            .iter()
            .any(|s| s.contains("PROGRAM_STOP"))
    );
    assert!(refusal_ok(
        "error: a.ngc:3: '#' parameters are not supported (expand them first)",
        "a.ngc"
    ));
    assert!(!refusal_ok(
        "error: <optimized>: not equivalent to a.ngc: cutting move counts differ: 1 vs 2",
        "a.ngc"
    ));
    assert!(!refusal_ok(
        "error: a.ngc: cannot find the safe height",
        "a.ngc"
    ));
}

#[test]
fn canon_air_and_lifts_are_counted() {
    if !rs274_or_notice() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (_, c) = replay_text(dir.path(), "p", PART);
    let (air, lifts) = canon_air_lifts(&c.calls);
    // 0,0,0 -> Z5 (5), -> X0 Y0 (0), lift Z-1 -> Z5 (6), X20 -> X30 (10), lift (6)
    assert!((air - 27.0).abs() < 1e-6, "{air}");
    assert_eq!(lifts, 1, "the last retract is followed by no cut");
}
