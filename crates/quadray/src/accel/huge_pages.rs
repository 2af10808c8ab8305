//! Room for the BVHs' nodes and blocks in memory the kernel is asked to back with transparent
//! huge pages. Every ray reads them at random: with 4 KiB pages a big mesh's read costs a TLB
//! miss as well as a cache miss, with 2 MiB pages far fewer (Embree's BVHs sit in huge pages on
//! Linux too).
//!
//! The advice must come before the memory is first touched (pages already in place stay small),
//! so the vector is returned empty, with its capacity advised, for the caller to fill.

/// Below this many bytes no whole huge page fits in an allocation, so it is not advised.
#[cfg(target_os = "linux")]
const HUGE_PAGE: usize = 2 << 20;

/// An empty vector with room for `len` items, whose untouched memory is advised to be backed by
/// huge pages (Linux; elsewhere a plain `Vec::with_capacity`).
pub(in crate::accel) fn vec_with_capacity<T>(len: usize) -> Vec<T> {
    let v = Vec::with_capacity(len);
    #[cfg(target_os = "linux")]
    {
        let bytes = len.saturating_mul(size_of::<T>());
        if bytes >= 2 * HUGE_PAGE {
            // SAFETY: sysconf reads a constant of the system.
            let page = usize::try_from(unsafe { libc::sysconf(libc::_SC_PAGESIZE) }).unwrap_or(0);
            let start = v.as_ptr() as usize;
            // The whole pages inside the allocation: advice never reaches memory not ours.
            if let (true, Some(lo)) = (page.is_power_of_two(), start.checked_next_multiple_of(page))
            {
                let hi = (start + bytes) & !(page - 1);
                if hi > lo {
                    // SAFETY: [lo, hi) lies inside the vector's allocation, which we own, and
                    // MADV_HUGEPAGE changes how it is backed, never its contents. A refusal (a
                    // kernel without transparent huge pages) leaves ordinary pages: ignored.
                    unsafe {
                        libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
                    }
                }
            }
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vector is empty with the room asked for, large or small, and fills as any vector.
    #[test]
    fn the_room_is_there_and_fills() {
        for len in [0, 3, 1 << 20] {
            let mut v: Vec<u64> = vec_with_capacity(len);
            assert!(v.is_empty() && v.capacity() >= len);
            v.extend((0..len as u64).map(|i| i * 3));
            assert!(v.iter().enumerate().all(|(i, &x)| x == i as u64 * 3));
        }
    }
}
