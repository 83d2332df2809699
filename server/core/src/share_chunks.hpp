// A loop of independent chunks shared by the calling thread and helper threads that do not hold it up (internal
// header; share_chunks.cpp). For a step's row loops: the detector's sweep (collision/parallel_sweep.hpp), the
// deformation (deformation_step.cpp), the history's row copies (row_copy.hpp) and the simplified detector's clusters
// (collision_simplified.cpp).
//
// An OpenMP parallel region ends at a barrier that every thread of its team must reach. On a busy machine a
// woken worker may wait for the scheduler's next tick (4 ms here) before it runs at all, and the calling thread,
// done with every chunk itself, waits for it at that barrier: steps of 0.3 ms took 4, 8 or 16 ms (RESULTS §35,
// §89). Here every thread claims one chunk at a time from a shared range (the caller at its front, helpers at its
// back), and the caller waits only for chunks a helper has claimed: a helper that was not running when the loop
// began finds nothing left and is never waited for. A helper descheduled while it holds a chunk is still waited
// for.
#pragma once

#include <exception>
#include <functional>

#include "surfeledit/core/types.hpp"

namespace surfeledit::detail {

// Runs chunk(c) once for every c in [0, chunks), on the calling thread and up to `threads` - 1 helpers (threads of
// one process-wide pool), in no fixed order: chunk() must give the same result whichever thread runs it and
// whenever. With threads <= 1 or a single chunk, in order on the calling thread. Returns once every chunk ran. A
// chunk that throws does not stop the others; the exception of the lowest such chunk is rethrown at the end, the
// same one whatever the threads. Callers on several threads at once share the pool.
void share_chunks(int threads, Index chunks, const std::function<void(Index)>& chunk);

// The pool's threads: one fewer than the hardware threads (the caller is the other), at least one.
int helper_threads();

}  // namespace surfeledit::detail
