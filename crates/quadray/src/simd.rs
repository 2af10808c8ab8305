//! The compiled paths of the hot loops (the traversal, camera rays, sample points): the target's
//! baseline and, on x86-64, AVX2 with FMA chosen at run time.

use std::sync::OnceLock;

/// Which compiled path runs on this machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdPath {
    /// The target's baseline instruction set (SSE2 on x86-64, NEON on aarch64).
    Baseline,
    /// x86-64 with AVX2 and FMA, detected at run time.
    Avx2,
}

impl std::fmt::Display for SimdPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SimdPath::Baseline if cfg!(target_arch = "aarch64") => "NEON",
            SimdPath::Baseline if cfg!(target_arch = "x86_64") => "SSE2",
            SimdPath::Baseline => "scalar",
            SimdPath::Avx2 => "AVX2+FMA",
        })
    }
}

/// The path chosen for this process: AVX2+FMA where the CPU has them, unless the
/// environment variable `QUADRAY_SIMD=baseline` asks for the baseline.
pub fn simd_path() -> SimdPath {
    static PATH: OnceLock<SimdPath> = OnceLock::new();
    *PATH.get_or_init(|| {
        if std::env::var("QUADRAY_SIMD").is_ok_and(|v| v == "baseline") {
            return SimdPath::Baseline;
        }
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            return SimdPath::Avx2;
        }
        SimdPath::Baseline
    })
}
