//! Replays, through the fuzz targets' own functions (`organtex::fuzz`),
//! every seed of the corpus (fuzz/corpus/<target>/) and every input the
//! fuzzer ever failed on (tests/data/fuzz-regressions/<target>/, copied
//! there by tools/fuzz.sh), so a fixed crash stays fixed without cargo-fuzz.
//!
//! A past failure may have been a hang or a runaway allocation, so each
//! one runs in a child process (this test binary again) with its address
//! space and time bounded, and fails when its peak resident memory passes
//! 512 MiB (libFuzzer's own limit is 2 GiB; these inputs are a few KB): an
//! unfixed one fails the test instead of hanging it or exhausting the
//! machine's memory.
//!
//! The fuzz build sets `cfg(fuzzing)`, under which the png crate skips its
//! CRC checks; a PNG the fuzzer found then fails here on its checksum
//! before it reaches the bug. Such a file sits beside a copy with its
//! checksums recomputed (`...-crc-fixed.png`), which reaches the bug in any
//! build.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use organtex::fuzz;

/// A fuzz target: never panics on any input.
type Target = fn(&[u8]);

const TARGETS: &[(&str, Target)] = &[
    ("obj", fuzz::obj),
    ("ply", fuzz::ply),
    ("stl", fuzz::stl),
    ("scene", fuzz::scene),
    ("db_index", fuzz::db_index),
    ("nrrd", fuzz::nrrd),
    ("nifti", fuzz::nifti),
    ("label_map", fuzz::label_map),
    ("vtk", fuzz::vtk),
    ("lst", fuzz::lst),
    ("image", fuzz::image),
    ("mask", fuzz::mask),
    ("carving", fuzz::carving),
];

/// Set in a child process: "TARGET:FILE" to replay.
const REPLAY: &str = "ORGANTEX_FUZZ_REPLAY";
/// A child's address space (KiB, for `ulimit -v`) and time.
const CHILD_MEMORY_KIB: u64 = 2 << 20;
const CHILD_TIME: Duration = Duration::from_secs(60);
/// A child's peak resident memory (KiB).
const CHILD_RSS_KIB: u64 = 512 << 10;

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries
        .map(|e| e.expect("a readable folder entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

fn target(name: &str) -> Target {
    TARGETS
        .iter()
        .find(|t| t.0 == name)
        .expect("a known target")
        .1
}

/// Replay one past failure in a bounded child; `Err` says how it failed.
fn replay_in_child(name: &str, file: &Path) -> Result<(), String> {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {CHILD_MEMORY_KIB} 2>/dev/null; exec \"$0\" --exact replay_one --nocapture --test-threads 1"
        ))
        .arg(std::env::current_exe().expect("the test binary"))
        .env(REPLAY, format!("{name}:{}", file.display()))
        .stdout(Stdio::null())
        .spawn()
        .expect("cannot start a child test process");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("waiting for the child") {
            return if status.success() {
                Ok(())
            } else {
                Err(format!("failed ({status})"))
            };
        }
        if start.elapsed() > CHILD_TIME {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("still running after {CHILD_TIME:?}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The child's side of `replay_in_child`; does nothing in a normal run.
#[test]
fn replay_one() {
    let Ok(spec) = std::env::var(REPLAY) else {
        return;
    };
    let (name, file) = spec.split_once(':').expect("TARGET:FILE");
    target(name)(&std::fs::read(file).expect("a readable input"));
    if let Some(peak) = peak_rss_kib() {
        assert!(
            peak <= CHILD_RSS_KIB,
            "{file}: peak resident memory {} MiB, over {} MiB",
            peak >> 10,
            CHILD_RSS_KIB >> 10
        );
    }
}

/// This process's peak resident memory (Linux's VmHWM), if known.
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[test]
fn every_seed_and_past_failure_passes_its_fuzz_target() {
    if std::env::var_os(REPLAY).is_some() {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut failures = Vec::new();
    for &(name, run) in TARGETS {
        let seeds = files(&root.join("fuzz/corpus").join(name));
        let regressions = files(&root.join("tests/data/fuzz-regressions").join(name));
        assert!(
            !seeds.is_empty(),
            "no seed in fuzz/corpus/{name}/: the target would pass untried"
        );
        for file in &seeds {
            let bytes = std::fs::read(file).expect("a readable input");
            if std::panic::catch_unwind(|| run(&bytes)).is_err() {
                failures.push(format!("{name}: {}: panicked", file.display()));
            }
        }
        for file in &regressions {
            if let Err(e) = replay_in_child(name, file) {
                failures.push(format!("{name}: {}: {e}", file.display()));
            }
        }
        eprintln!(
            "{name}: {} seeds, {} past failures",
            seeds.len(),
            regressions.len()
        );
    }
    assert!(
        failures.is_empty(),
        "these inputs fail their fuzz target (messages above):\n{}",
        failures.join("\n")
    );
}
