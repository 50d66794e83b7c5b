//! The allocator setting of the `bodyseg` binary (`bodyseg_pipeline::keep_freed_memory`,
//! which refine cannot depend on), for the benches and examples that time refine the way
//! `bodyseg refine` runs it.

/// mimalloc's `mi_option_purge_delay` (its `mi_option_e` in `mimalloc.h`, v2 and v3).
const MI_OPTION_PURGE_DELAY: libmimalloc_sys::mi_option_t = 15;

/// Tells mimalloc never to hand freed memory back to the OS, as the binary does: without
/// it every refinement pays a page fault and a page clear for each page of its arrays
/// again (7–12 % of the refinement's time in `perf record` on the 100k synth cloud).
pub fn keep_freed_memory() {
    // SAFETY: `mi_option_set` only stores an integer in mimalloc's option table (an
    // atomic write); any value of this option is valid, at any time.
    #[allow(unsafe_code)]
    unsafe {
        libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DELAY, -1);
    }
}
