//! The memory a render may use: what the machine has free, so that a render too large for it is
//! refused with a clear error before it starts instead of being killed (or aborted by a failed
//! allocation) part way.

use std::path::Path;

/// Environment variable that sets the free memory in bytes, in place of what the system reports:
/// for a shared machine whose free memory is not the job's, and for tests.
pub const AVAILABLE_MEMORY_VAR: &str = "QUADRAY_AVAILABLE_MEMORY";

/// Why the free memory could not be read.
#[derive(Debug, thiserror::Error)]
pub enum MemoryError {
    /// [`AVAILABLE_MEMORY_VAR`] is set to something other than a whole number of bytes.
    #[error("{AVAILABLE_MEMORY_VAR}={0:?} is not a whole number of bytes")]
    BadOverride(String),
}

/// Bytes of memory free for a render: [`AVAILABLE_MEMORY_VAR`] when set, else on Linux the least of
/// the kernel's estimate of available memory (`MemAvailable` in /proc/meminfo), what the
/// process's cgroup (v2) limit leaves and what its address-space limit (`ulimit -v`) leaves;
/// `None` where none is known.
pub fn available_bytes() -> Result<Option<u64>, MemoryError> {
    if let Some(value) = std::env::var_os(AVAILABLE_MEMORY_VAR) {
        let text = value.to_string_lossy().into_owned();
        return text
            .trim()
            .parse()
            .map(Some)
            .map_err(|_| MemoryError::BadOverride(text));
    }
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let available = read("/proc/meminfo").as_deref().and_then(mem_available);
    let cgroup = cgroup_room(Path::new("/sys/fs/cgroup"));
    let address_space = (read("/proc/self/limits").as_deref())
        .zip(read("/proc/self/status").as_deref())
        .and_then(|(limits, status)| address_space_room(limits, status));
    Ok([available, cgroup, address_space]
        .into_iter()
        .flatten()
        .min())
}

/// What the soft address-space limit of a /proc/self/limits text leaves, less the `VmSize` of a
/// /proc/self/status text; `None` without a limit.
fn address_space_room(limits: &str, status: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line.split_whitespace().nth(3)?.parse().ok()?;
    let size = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let kib: u64 = size.split_whitespace().nth(1)?.parse().ok()?;
    Some(soft.saturating_sub(kib.saturating_mul(1024)))
}

/// `MemAvailable` of a /proc/meminfo text, in bytes.
fn mem_available(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// What the cgroup v2 memory limit in `root` leaves (`memory.max` less `memory.current`); `None`
/// without a limit ("max") or a cgroup v2 hierarchy.
fn cgroup_room(root: &Path) -> Option<u64> {
    let read = |name: &str| std::fs::read_to_string(root.join(name)).ok();
    let max: u64 = read("memory.max")?.trim().parse().ok()?;
    let current: u64 = read("memory.current")?.trim().parse().ok()?;
    Some(max.saturating_sub(current))
}

/// A byte count for people: "1.9 GB", "350 MB", "12 kB".
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    match bytes {
        0..1_000_000 => format!("{:.0} kB", b / 1e3),
        1_000_000..1_000_000_000 => format!("{:.0} MB", b / 1e6),
        _ => format!("{:.1} GB", b / 1e9),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_and_cgroup_limits_are_read() {
        let meminfo =
            "MemTotal:       24684084 kB\nMemFree:  100 kB\nMemAvailable:   24205676 kB\n";
        assert_eq!(mem_available(meminfo), Some(24_205_676 * 1024));
        assert_eq!(mem_available("MemTotal: 5 kB\n"), None);
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(cgroup_room(dir.path()), None);
        std::fs::write(dir.path().join("memory.max"), "max\n").unwrap();
        std::fs::write(dir.path().join("memory.current"), "1000\n").unwrap();
        assert_eq!(cgroup_room(dir.path()), None);
        std::fs::write(dir.path().join("memory.max"), "4096\n").unwrap();
        assert_eq!(cgroup_room(dir.path()), Some(3096));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes\n";
        let limited = "Max cpu time   unlimited  unlimited  seconds\n\
                       Max address space         3072000000           3072000000           bytes\n";
        let status = "Name:\tquadray\nVmSize:\t    3892 kB\n";
        assert_eq!(address_space_room(unlimited, status), None);
        assert_eq!(
            address_space_room(limited, status),
            Some(3_072_000_000 - 3892 * 1024)
        );
        assert_eq!(human_bytes(12_000), "12 kB");
        assert_eq!(human_bytes(350_000_000), "350 MB");
        assert_eq!(human_bytes(1_870_000_000), "1.9 GB");
    }
}
