#pragma once
// Runs work inside a TBB arena of `threads` threads, so that the parallel loops in it use that
// many (0: in the caller's arena, every core by default). The `--threads` option of the fit and
// the evaluator's batch calls go through here. Internal.

#include <tbb/task_arena.h>

namespace tbs::detail {

template <class F>
void with_threads(int threads, F&& f) {
  if (threads > 0)
    tbb::task_arena(threads).execute(f);
  else
    f();
}

}  // namespace tbs::detail
