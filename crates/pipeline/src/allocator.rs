//! Settings of mimalloc, the allocator of the `bodyseg` binary and of the benches.

/// mimalloc's `mi_option_purge_delay` (its `mi_option_e` in `mimalloc.h`, v2 and v3).
const MI_OPTION_PURGE_DELAY: libmimalloc_sys::mi_option_t = 15;

/// Tells mimalloc never to hand freed memory back to the OS (`purge_delay = -1`). Call it
/// first thing in `main` of a program whose global allocator is `mimalloc::MiMalloc`;
/// without that allocator it changes nothing that matters.
///
/// Why: every frame allocates and frees the same tens of megabytes (clouds, per-person
/// arrays, label images, encoders). With purging, mimalloc returns them to the kernel and
/// the next frame pays a page fault and a page clear for each page again: 16 000 page
/// faults against 370 over the same 72 frames and ~9% more CPU time (`perf stat -e
/// page-faults,task-clock` on `crates/lab/examples/cpu_per_frame.rs`, with and
/// without `PURGE=1`). The
/// memory stays at its high-water mark instead, which is flat over a run: one frame per
/// worker.
pub fn keep_freed_memory() {
    // SAFETY: `mi_option_set` only stores an integer in mimalloc's option table (an
    // atomic write); any value of this option is valid, and the call may come at any
    // time, before or after the first allocation.
    #[allow(unsafe_code)]
    unsafe {
        libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DELAY, -1);
    }
}
