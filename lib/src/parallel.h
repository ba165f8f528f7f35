// The one wrapper around TBB: every parallel loop in the library goes through here.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>
#include <utility>

namespace ssgi::detail {

// Calls body(y) for every row y in [0, rows), in parallel. Rows are independent and each
// writes only its own outputs, so the result does not depend on the thread count.
template <typename Body>
void parallel_for_rows(int rows, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y < r.end(); ++y) body(y);
  });
}

// One T for each thread that asks for it in a parallel loop (local()), each made on its first
// use in that thread; all of them visited afterwards by iterating.
template <typename T>
using PerThread = tbb::enumerable_thread_specific<T>;

// Sets the `count` values from `first` on to `value`, in parallel blocks: filling (and first
// touching the pages of) a frame-sized buffer on one thread is a serial part of the frame.
template <typename T>
void parallel_fill(T* first, std::size_t count, const T& value) {
  constexpr std::size_t kBlockBytes = std::size_t{1} << 17;
  const std::size_t block = std::max<std::size_t>(1, kBlockBytes / sizeof(T));
  if (count <= 2 * block) {
    std::fill(first, first + count, value);
    return;
  }
  parallel_for_rows(static_cast<int>((count + block - 1) / block), [&](int b) {
    const std::size_t begin = static_cast<std::size_t>(b) * block;
    std::fill(first + begin, first + std::min(count, begin + block), value);
  });
}

// How many threads the loops above may use now (--threads, a ThreadLimit, or the machine's).
inline int worker_threads() {
  return static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

// Runs items 0, 1, ... through three stages, first(i) -> A, middle(A) -> B, last(B), until
// first's item index reaches `count` or more_items() turns false. Each stage takes one item at a
// time and the items in order; up to `in_flight` items are between first and last at once, so
// that item i + 1's first stage and item i - 1's last overlap with item i's middle (1: one
// after the other). Each stage's own parallel loops run isolated: a thread waiting for them
// does not pick up another stage's item meanwhile. A and B must be movable.
template <typename A, typename B, typename First, typename Middle, typename Last,
          typename MoreItems>
void pipeline_in_order(int count, int in_flight, const First& first, const Middle& middle,
                       const Last& last, const MoreItems& more_items) {
  int next = 0;
  const auto in_order = tbb::filter_mode::serial_in_order;
  tbb::parallel_pipeline(
      static_cast<std::size_t>(std::max(1, in_flight)),
      tbb::make_filter<void, A>(in_order, [&](tbb::flow_control& control) -> A {
        if (next >= count || !more_items()) {
          control.stop();
          return A();
        }
        const int i = next++;
        return tbb::this_task_arena::isolate([&] { return first(i); });
      }) & tbb::make_filter<A, B>(in_order, [&](A a) -> B {
        return tbb::this_task_arena::isolate([&] { return middle(std::move(a)); });
      }) & tbb::make_filter<B, void>(in_order, [&](B b) {
        tbb::this_task_arena::isolate([&] { last(std::move(b)); });
      }));
}

}  // namespace ssgi::detail
