// jemalloc's options for the mbsgen tool, compiled in only when the tool links jemalloc
// (generator/CMakeLists.txt); jemalloc reads this symbol at start-up, and the environment
// variable MALLOC_CONF still overrides it.
//
// thp:always asks the kernel for transparent huge pages (madvise) for the heap, metadata_thp for
// jemalloc's own tables. A large model's derivation touches a few hundred MB of GiNaC nodes once
// each: with 4 KiB pages the 40-link spatial chain took about 135,000 page faults, a tenth of its
// generation time in the kernel; with huge pages about 6,000, and 8.2 → 6.6 CPU-s (three runs
// each, in turn), for 6 % more peak memory (410 → 433 MB). Where the kernel has huge pages off
// ("never"), the option does nothing.
//
// dirty_decay_ms:30000 keeps freed pages for 30 s (jemalloc's default: 10 s) before it returns
// them to the kernel. A generation frees and allocates again as it goes; returned huge pages were
// faulted in and zeroed anew, and the purging ran in the allocating thread: the 40-link chain
// spent 0.4-1.2 s in the kernel with the default, 0.45 s with 30 s (user time 4.8 → 4.5 s, the
// peak the same, 445 MB; alternating runs). Never returning them (-1) grew the peak by 8 %.
//
// oversize_threshold:0 serves allocations above 8 MiB from the ordinary arenas too: jemalloc's
// default gives them an arena that returns their pages at once, and the generator's large hash
// tables (CSE's, the canonical-order memo growing), allocated and freed again and again, were
// then faulted in and zeroed each time, the largest part of the kernel time left (40-link chain:
// 0.47-1.01 s of system time in three runs, 0.45-0.56 s without).
extern "C" {
// NOLINTNEXTLINE(cppcoreguidelines-avoid-non-const-global-variables): jemalloc's interface
const char* malloc_conf = "thp:always,metadata_thp:always,dirty_decay_ms:30000,oversize_threshold:0";
}
