//! A global allocator that can cap the heap of one fuzz case.
//!
//! Unarmed (always, except inside `meshletlab fuzz-worker` while a case runs) it costs one relaxed
//! atomic load per call and passes straight to the system allocator. Armed, it counts live bytes
//! and refuses (returns null) any request that would take them past the limit: Rust then aborts
//! with "memory allocation of N bytes failed", and the parent process reports the case as an
//! over-limit allocation. Refusing instead of serving means a header that asks for 48 GB never
//! touches the machine's memory. Blocks allocated before [`arm`] and freed during a case count as
//! freed, which can only loosen the cap by what was live before the case (a few kilobytes here).
//!
//! Install it in a binary with `#[global_allocator] static A: LimitAlloc = LimitAlloc;`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicIsize, Ordering::Relaxed};

/// The allocator (a unit struct; all state is in statics, one per process).
pub struct LimitAlloc;

static ARMED: AtomicBool = AtomicBool::new(false);
static LIMIT: AtomicIsize = AtomicIsize::new(isize::MAX);
static LIVE: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);

/// Starts counting from zero with a cap of `limit` live bytes.
pub fn arm(limit: usize) {
    LIVE.store(0, Relaxed);
    PEAK.store(0, Relaxed);
    LIMIT.store(limit.min(isize::MAX as usize) as isize, Relaxed);
    ARMED.store(true, Relaxed);
}

/// Stops counting; returns the peak of live bytes since [`arm`].
pub fn disarm() -> usize {
    ARMED.store(false, Relaxed);
    PEAK.load(Relaxed).max(0) as usize
}

/// Whether [`LimitAlloc`] is this process's global allocator (it counts a test allocation).
pub fn installed() -> bool {
    arm(usize::MAX);
    let probe = std::hint::black_box(vec![0u8; 4096]);
    drop(probe);
    disarm() >= 4096
}

/// Adds `n` bytes; false (and nothing added) if that passes the limit.
fn charge(n: usize) -> bool {
    let n = n.min(isize::MAX as usize) as isize;
    let now = LIVE.fetch_add(n, Relaxed).saturating_add(n);
    if now > LIMIT.load(Relaxed) {
        LIVE.fetch_sub(n, Relaxed);
        return false;
    }
    PEAK.fetch_max(now, Relaxed);
    true
}

fn release(n: usize) {
    LIVE.fetch_sub(n.min(isize::MAX as usize) as isize, Relaxed);
}

/// Charges `size` (when armed) and allocates with `f`; refuses with null past the limit and undoes
/// the charge when the system allocator fails.
fn counted(size: usize, f: impl FnOnce() -> *mut u8) -> *mut u8 {
    let armed = ARMED.load(Relaxed);
    if armed && !charge(size) {
        return std::ptr::null_mut();
    }
    let p = f();
    if armed && p.is_null() {
        release(size);
    }
    p
}

// SAFETY: every call is forwarded to `System` with the caller's layout, or answered with null
// (allowed: it means allocation failure). The counters never affect the memory handed out.
unsafe impl GlobalAlloc for LimitAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        counted(layout.size(), || unsafe { System.alloc(layout) })
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        counted(layout.size(), || unsafe { System.alloc_zeroed(layout) })
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if ARMED.load(Relaxed) {
            release(layout.size());
        }
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let armed = ARMED.load(Relaxed);
        let grow = new_size.saturating_sub(layout.size());
        if armed && grow > 0 && !charge(grow) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if armed {
            if p.is_null() {
                // The old block stays as it was.
                release(grow);
            } else {
                release(layout.size().saturating_sub(new_size));
            }
        }
        p
    }
}
