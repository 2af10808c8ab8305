//! The memory a render may use: what the machine has free, so that a render too large for it is
//! refused with a clear error before it starts instead of being killed (or aborted by a failed
//! allocation) part way.

use std::path::{Path, PathBuf};

/// Environment variable that sets the free memory in bytes, in place of what the system reports:
/// for a shared machine whose free memory is not the job's, and for tests. Empty: unset.
pub const AVAILABLE_MEMORY_VAR: &str = "QUADRAY_AVAILABLE_MEMORY";

/// Why the free memory could not be read.
#[derive(Debug, thiserror::Error)]
pub enum MemoryError {
    /// [`AVAILABLE_MEMORY_VAR`] is set to something other than a whole number of bytes.
    #[error("{AVAILABLE_MEMORY_VAR}={0:?} is not a whole number of bytes")]
    BadOverride(String),
}

/// Bytes of memory free for a render: [`AVAILABLE_MEMORY_VAR`] when set, else on Linux the least
/// of the kernel's estimate of available memory (`MemAvailable` in /proc/meminfo), what the
/// memory limits of the process's control group and its ancestors leave (cgroup v2 or v1, the
/// reclaimable file cache not counted as used) and what its address-space limit (`ulimit -v`)
/// leaves; `None` where none is known.
pub fn available_bytes() -> Result<Option<u64>, MemoryError> {
    if let Some(value) = std::env::var_os(AVAILABLE_MEMORY_VAR).filter(|v| !v.is_empty()) {
        let text = value.to_string_lossy().into_owned();
        return text
            .trim()
            .parse()
            .map(Some)
            .map_err(|_| MemoryError::BadOverride(text));
    }
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let available = read("/proc/meminfo").as_deref().and_then(mem_available);
    let cgroup = (read("/proc/self/cgroup").as_deref())
        .and_then(|groups| cgroup_room(Path::new("/sys/fs/cgroup"), groups));
    let address_space = (read("/proc/self/limits").as_deref())
        .zip(read("/proc/self/status").as_deref())
        .and_then(|(limits, status)| address_space_room(limits, status));
    Ok([available, cgroup, address_space]
        .into_iter()
        .flatten()
        .min())
}

/// `MemAvailable` of a /proc/meminfo text, in bytes.
fn mem_available(meminfo: &str) -> Option<u64> {
    kib_field(meminfo, "MemAvailable:")
}

/// A `NAME: <n> kB` field of a /proc text, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The files of one cgroup version's memory controller.
struct Controller {
    /// Where its hierarchy is mounted, under the cgroup root.
    mount: &'static str,
    /// The limit (`max` or a number).
    limit: &'static str,
    /// The memory charged, page cache included.
    usage: &'static str,
    /// The field of `memory.stat` holding the reclaimable (inactive) file cache.
    inactive_file: &'static str,
}

/// cgroup v2 (the unified hierarchy).
const V2: Controller = Controller {
    mount: "",
    limit: "memory.max",
    usage: "memory.current",
    inactive_file: "inactive_file",
};

/// cgroup v1's memory controller.
const V1: Controller = Controller {
    mount: "memory",
    limit: "memory.limit_in_bytes",
    usage: "memory.usage_in_bytes",
    inactive_file: "total_inactive_file",
};

/// The least room the memory limits of the process's control group and its ancestors leave,
/// from the cgroup hierarchies under `root` and the process's /proc/self/cgroup text `groups`:
/// each limit less the memory charged to its group, whose inactive file cache the kernel
/// reclaims before it runs out (charged memory counts it, and after a build or a large read it is
/// most of it). `None` without any limit.
fn cgroup_room(root: &Path, groups: &str) -> Option<u64> {
    let mut rooms = Vec::new();
    for line in groups.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) =
            (fields.next(), fields.next(), fields.next())
        else {
            continue;
        };
        let controller = match controllers {
            "" => V2,
            c if c.split(',').any(|c| c == "memory") => V1,
            _ => continue,
        };
        let mount = root.join(controller.mount);
        let mut dir: PathBuf = mount.join(path.trim_start_matches('/'));
        loop {
            rooms.extend(group_room(&dir, &controller));
            if dir == mount || !dir.pop() || !dir.starts_with(&mount) {
                break;
            }
        }
    }
    rooms.into_iter().min()
}

/// The room one group's memory limit leaves (see [`cgroup_room`]); `None` without a limit (`max`,
/// or v1's near-2⁶³ "unlimited") or the files.
fn group_room(dir: &Path, controller: &Controller) -> Option<u64> {
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
    let limit: u64 = read(controller.limit)?.trim().parse().ok()?;
    if limit >= 1 << 60 {
        return None;
    }
    let usage: u64 = read(controller.usage)?.trim().parse().ok()?;
    let stat = read("memory.stat").unwrap_or_default();
    let inactive_file: u64 = (stat.lines())
        .find_map(|l| l.strip_prefix(controller.inactive_file)?.strip_prefix(' '))
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or(0);
    Some(limit.saturating_sub(usage.saturating_sub(inactive_file)))
}

/// What the soft address-space limit of a /proc/self/limits text leaves, less the `VmSize` of a
/// /proc/self/status text; `None` without a limit. The render's threads reserve their stacks
/// and allocator arenas later, so a render that passes may still meet the limit.
fn address_space_room(limits: &str, status: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line.split_whitespace().nth(3)?.parse().ok()?;
    Some(soft.saturating_sub(kib_field(status, "VmSize:")?))
}

/// A byte count for people: "12 kB", "350 MB", "1.9 GB" (the unit chosen after rounding, so
/// 999 999 bytes is "1 MB").
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    if (b / 1e3).round() < 1000.0 {
        format!("{:.0} kB", b / 1e3)
    } else if (b / 1e6).round() < 1000.0 {
        format!("{:.0} MB", b / 1e6)
    } else {
        format!("{:.1} GB", b / 1e9)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_and_address_space_limits_are_read() {
        let meminfo =
            "MemTotal:       24684084 kB\nMemFree:  100 kB\nMemAvailable:   24205676 kB\n";
        assert_eq!(mem_available(meminfo), Some(24_205_676 * 1024));
        assert_eq!(mem_available("MemTotal: 5 kB\n"), None);
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
        assert_eq!(human_bytes(999_999), "1 MB");
        assert_eq!(human_bytes(350_000_000), "350 MB");
        assert_eq!(human_bytes(999_999_999), "1.0 GB");
        assert_eq!(human_bytes(1_870_000_000), "1.9 GB");
    }

    /// The process's own group and its ancestors are read, in either cgroup version; the
    /// inactive file cache counts as free; "max" and v1's "unlimited" are no limit.
    #[test]
    fn cgroup_limits_up_the_tree_are_read() {
        let write = |dir: &Path, files: &[(&str, &str)]| {
            std::fs::create_dir_all(dir).unwrap();
            for (name, text) in files {
                std::fs::write(dir.join(name), text).unwrap();
            }
        };
        // cgroup v2: a job at /farm/job with no limit of its own, under /farm limited to 4 GB
        // with 3 GB charged, 2 GB of it inactive file cache.
        let root = tempfile::tempdir().unwrap();
        write(&root.path().join("farm/job"), &[("memory.max", "max\n")]);
        let stat = "anon 1000\ninactive_file 2000000000\nactive_file 5\n";
        let farm = [
            ("memory.max", "4000000000\n"),
            ("memory.current", "3000000000\n"),
            ("memory.stat", stat),
        ];
        write(&root.path().join("farm"), &farm);
        assert_eq!(
            cgroup_room(root.path(), "0::/farm/job\n"),
            Some(3_000_000_000)
        );
        assert_eq!(cgroup_room(root.path(), "0::/\n"), None);
        // cgroup v1 (a hybrid host): the memory controller's own hierarchy.
        let root = tempfile::tempdir().unwrap();
        let group = root.path().join("memory/api/42");
        let v1 = [
            ("memory.limit_in_bytes", "2000000000\n"),
            ("memory.usage_in_bytes", "1500000000\n"),
            (
                "memory.stat",
                "inactive_file 7\ntotal_inactive_file 1000000000\n",
            ),
        ];
        write(&group, &v1);
        write(
            &root.path().join("memory"),
            &[("memory.limit_in_bytes", "9223372036854771712\n")],
        );
        let groups = "4:memory:/api/42\n1:cpu,cpuacct:/\n0::/\n";
        assert_eq!(cgroup_room(root.path(), groups), Some(1_500_000_000));
    }
}
