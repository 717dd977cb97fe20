//! Refusing work too large for the machine before allocating it, so that a
//! huge size in a file or on the command line gives an error with the
//! estimate instead of the kernel killing the process.
//!
//! The estimates are of what the stages really hold at their peak; they
//! are approximate (within a factor of about 1.5), enough to tell a job
//! that fits from one that cannot. Each stage makes its own (it knows its
//! sizes: `synth::fnpts::memory_bytes`, `synth::block::memory_bytes`,
//! the tet mesher's); this file keeps the budget and the refusal.

use crate::error::{Error, Result};

/// Assumed available memory when /proc/meminfo cannot be read (not Linux,
/// or a sandbox hiding it).
pub const FALLBACK_AVAILABLE: u64 = 8 << 30;

/// Environment variable that caps the memory organtex plans to use below
/// what the machine has (bytes, or with a K, M or G suffix), for shared
/// machines and for tests.
pub const LIMIT_VAR: &str = "ORGANTEX_MEMORY_LIMIT";

/// Refuse `what` if it needs more than `bytes` the machine has available.
pub fn ensure_fits(what: &str, bytes: u64) -> Result<()> {
    check(what, bytes).map_err(Error::invalid)
}

/// `ensure_fits` with the message alone, for callers that place it in a
/// file and line themselves.
pub fn check(what: &str, bytes: u64) -> std::result::Result<(), String> {
    let (available, source) = available()?;
    if bytes <= available {
        return Ok(());
    }
    Err(format!(
        "{what} needs about {} GiB, this machine has {} GiB available{source}",
        gib(bytes),
        gib(available)
    ))
}

/// The memory available, and where the figure comes from (empty when it is
/// the kernel's MemAvailable).
fn available() -> std::result::Result<(u64, &'static str), String> {
    let (machine, mut source) = match meminfo_available() {
        Some(b) => (b, ""),
        None => (
            FALLBACK_AVAILABLE,
            " (assumed: /proc/meminfo gives no MemAvailable)",
        ),
    };
    let mut available = machine;
    if let Some(value) = std::env::var_os(LIMIT_VAR) {
        let value = value.to_string_lossy();
        let limit = parse_size(&value)
            .ok_or_else(|| format!("{LIMIT_VAR}='{value}' is not a size such as 512M or 4G"))?;
        if limit < available {
            available = limit;
            source = " (capped by ORGANTEX_MEMORY_LIMIT)";
        }
    }
    Ok((available, source))
}

/// MemAvailable from /proc/meminfo, in bytes.
fn meminfo_available() -> Option<u64> {
    parse_meminfo(&std::fs::read_to_string("/proc/meminfo").ok()?)
}

/// The MemAvailable line of a meminfo text ("MemAvailable: 123 kB").
fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// "123", "64K", "512M", "4G" (binary units), as bytes.
fn parse_size(s: &str) -> Option<u64> {
    let s = s.trim();
    let (digits, shift) = match s.chars().last()?.to_ascii_uppercase() {
        'K' => (&s[..s.len() - 1], 10),
        'M' => (&s[..s.len() - 1], 20),
        'G' => (&s[..s.len() - 1], 30),
        _ => (s, 0),
    };
    digits.trim().parse::<u64>().ok()?.checked_mul(1 << shift)
}

/// Bytes as GiB with two significant figures or more.
fn gib(bytes: u64) -> String {
    let g = bytes as f64 / (1u64 << 30) as f64;
    if g >= 10.0 {
        format!("{g:.0}")
    } else if g >= 1.0 {
        format!("{g:.1}")
    } else {
        format!("{g:.2}")
    }
}

/// `a * b * ...` in u64, saturating: an estimate that overflows is simply
/// too large.
pub fn product(factors: &[u64]) -> u64 {
    factors.iter().fold(1u64, |p, &f| p.saturating_mul(f))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_binary_units() {
        assert_eq!(parse_size("123"), Some(123));
        assert_eq!(parse_size("64k"), Some(64 << 10));
        assert_eq!(parse_size(" 512M "), Some(512 << 20));
        assert_eq!(parse_size("4G"), Some(4 << 30));
        assert_eq!(parse_size("G"), None);
        assert_eq!(parse_size("-1G"), None);
        assert_eq!(parse_size("99999999999G"), None);
    }

    #[test]
    fn meminfo_gives_available_bytes_or_nothing() {
        let text = "MemTotal:       32000000 kB\nMemFree:  100 kB\nMemAvailable:   23847632 kB\n";
        assert_eq!(parse_meminfo(text), Some(23_847_632 * 1024));
        // An old kernel without the line, or garbage: the fallback is used.
        assert_eq!(parse_meminfo("MemTotal: 1000 kB\nMemFree: 10 kB\n"), None);
        assert_eq!(parse_meminfo("MemAvailable: lots kB\n"), None);
    }

    #[test]
    fn an_impossible_size_is_refused_with_its_estimate() {
        let err = check("a test", u64::MAX).unwrap_err();
        assert!(err.starts_with("a test needs about 17179869184 GiB, this machine has "));
        assert!(err.contains(" GiB available"), "{err}");
        assert!(check("a test", 1).is_ok());
    }

    #[test]
    fn products_saturate_and_sizes_print_in_gib() {
        assert_eq!(product(&[u64::MAX, 2]), u64::MAX);
        assert_eq!(product(&[3, 0, 7]), 0);
        assert_eq!(gib(3 << 29), "1.5");
        assert_eq!(gib(1 << 28), "0.25");
    }
}
