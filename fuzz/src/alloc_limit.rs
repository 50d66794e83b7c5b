//! The global allocator of every fuzz build: the system allocator, refusing any request
//! that would take the live heap past [`LIMIT_BYTES`].
//!
//! Why not only libFuzzer's `-rss_limit_mb`: a reader that trusts a header and calls
//! `Vec::with_capacity(3_600_000_000)` gets address space that the kernel backs only when
//! touched, so the resident size never shows it, yet the same file would abort a run on a
//! machine without overcommit. `-malloc_limit_mb` would catch it, but libFuzzer sees
//! mallocs only through a sanitizer runtime, which stable Rust cannot link. A refused
//! request is an allocation failure: `Vec`, `String` and `Box` then abort with "memory
//! allocation of N bytes failed", which libFuzzer records as a crash with its input.
#![allow(unsafe_code)] // A `GlobalAlloc` is an unsafe trait; each call forwards to `System`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Most bytes the fuzzed code may hold at once: 2 GiB, the issue's bound for "an
/// allocation over 2 GB" (issue 27); libFuzzer's RSS limit in `scripts/fuzz.sh` is the
/// same.
pub const LIMIT_BYTES: usize = 2 << 30;

/// Live bytes handed out and not yet freed.
static LIVE: AtomicUsize = AtomicUsize::new(0);

/// The system allocator with a ceiling on the live heap.
pub struct LimitedAlloc;

impl LimitedAlloc {
    /// Books `size` more live bytes; false (booking nothing) past the limit.
    fn book(size: usize) -> bool {
        LIVE.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |live| {
            live.checked_add(size).filter(|&after| after <= LIMIT_BYTES)
        })
        .is_ok()
    }

    fn release(size: usize) {
        LIVE.fetch_sub(size, Ordering::Relaxed);
    }

    /// `allocate`'s block of `size` bytes, booked: null without calling it past the limit,
    /// and the booking given back when it fails.
    fn booked(size: usize, allocate: impl FnOnce() -> *mut u8) -> *mut u8 {
        if !Self::book(size) {
            return std::ptr::null_mut();
        }
        let p = allocate();
        if p.is_null() {
            Self::release(size);
        }
        p
    }
}

// SAFETY: every method forwards to `System` with the caller's layout unchanged, or
// returns null (a valid "allocation failed" answer) without calling it; the bookkeeping
// touches only an atomic counter and never allocates.
unsafe impl GlobalAlloc for LimitedAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's layout (non-zero size, GlobalAlloc's contract).
        Self::booked(layout.size(), || unsafe { System.alloc(layout) })
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as in `alloc`.
        Self::booked(layout.size(), || unsafe { System.alloc_zeroed(layout) })
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` with this layout (every allocation goes through
        // this allocator).
        unsafe { System.dealloc(ptr, layout) };
        Self::release(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old && !Self::book(new_size - old) {
            return std::ptr::null_mut();
        }
        // SAFETY: `ptr` came from `System` with `layout`; `new_size` is the caller's.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            if new_size > old {
                Self::release(new_size - old);
            }
        } else if new_size < old {
            Self::release(old - new_size);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: LimitedAlloc = LimitedAlloc;
