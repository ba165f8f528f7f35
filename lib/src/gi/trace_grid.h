// The trace grid: the pixels rays start from, and what rays meet there. At trace scale 1 it is
// every pixel; at scale s each s x s block of the data window traces from one pixel of its own (the
// one nearest the block's median depth, the surface most of the block shows), so that the tracer
// runs at the resolution the denoiser filters at, and the denoiser's pyramid takes the result from
// there. Hits name trace samples, whose light they bring: the tracers run at the trace grid's size
// (its few megabytes stay in cache), not at the frame's.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "buffers.h"
#include "parallel.h"
#include "ssgi/gbuffer.h"
#include "ssgi/image.h"

namespace ssgi::detail {

struct TraceGrid {
  int scale = 1;              // 1, 2 or 4: data-window pixels per trace sample, each axis
  int width = 0, height = 0;  // trace samples across and down
  // Per trace sample: the full-resolution pixel index it traces from, or -1 (no surface).
  std::vector<std::int32_t> origin;
  // What rays meet, per trace sample: the surface at the block's centre (the plane of its
  // origin pixel there; +inf where there is none), that pixel's normal, and the mean
  // reflected light and albedo (clamped to [0, 1]) of the block's pixels on its surface. At
  // scale 1 these are the frame's own values, so the mesh is the frame's (surface_model.h).
  Image depth, normal, reflected, albedo;
  // Per trace sample, its slab's thickness (surface_model.h: feature_thickness).
  Image thickness;
  // The camera in trace-sample units: the data window's pixel coordinates divided by scale.
  float fx = 1, fy = 1, cx = 0, cy = 0;
};

// The grid of trace origins for `g` at `scale`, with what rays meet there: the light its
// surfaces reflect is their direct light, plus their emission when `with_emission`; a block's
// pixels within `thickness` x depth of its origin's are on its surface.
TraceGrid make_trace_grid(const GBuffer& g, bool with_emission, int scale, float thickness);

// Entries that rows traced in parallel make, held until they are joined in row order
// (join_rows): each thread copies the rows it finishes, one after the other, into blocks of its
// own from allocate_block, so that a frame's entries fault in a few 2 MB pages rather than a
// vector per row in 4 KB ones (page faults are slow, and one thread's wait for another's:
// tests/bench/README.md, "Rendered 1080p and 4K"). The blocks are held until the RowEntries
// goes, so that joining holds the entries twice (a 1080p frame's hits: 16 MB, against the
// frame's 8 MB planes).
template <typename T>
class RowEntries {
 public:
  explicit RowEntries(int rows) : rows_(static_cast<std::size_t>(rows)) {}
  // Row `row`'s `n` entries from `first`: once per row, from the thread that traced it.
  void put(int row, const T* first, std::size_t n) {
    Blocks& own = blocks_.local();
    if (own.blocks.empty() || own.used + n > own.blocks.back().size()) {
      own.blocks.emplace_back();
      own.blocks.back().resize(std::max(kBlockBytes / sizeof(T), n));
      own.used = 0;
    }
    T* to = own.blocks.back().data() + own.used;
    std::copy(first, first + n, to);
    own.used += n;
    rows_[row] = {to, n};
  }
  std::size_t size(int row) const { return rows_[row].size; }
  const T* begin(int row) const { return rows_[row].first; }
  const T* end(int row) const { return rows_[row].first + rows_[row].size; }

 private:
  static constexpr std::size_t kBlockBytes = std::size_t{2} << 20;  // a huge page
  struct Blocks {
    std::vector<UninitializedVector<T>> blocks;
    std::size_t used = 0;  // of the last block
  };
  struct Row {
    const T* first = nullptr;
    std::size_t size = 0;
  };
  PerThread<Blocks> blocks_;
  std::vector<Row> rows_;
};

// join_rows' access to a RowEntries' rows and to a vector per row.
template <typename T>
std::size_t row_size(const RowEntries<T>& rows, int by) {
  return rows.size(by);
}
template <typename Entries>
std::size_t row_size(const std::vector<Entries>& rows, int by) {
  return rows[by].size();
}
template <typename T, typename To>
void move_row(RowEntries<T>& rows, int by, To to) {
  std::copy(rows.begin(by), rows.end(by), to);
}
template <typename Entries, typename To>
void move_row(std::vector<Entries>& rows, int by, To to) {
  std::copy(rows[by].begin(), rows[by].end(), to);
  rows[by] = Entries();
}

// Entries the trace samples made row by row in parallel, joined in trace-sample order: row by's
// entries (`rows`: a RowEntries, or a vector per row) are count(by, bx) for each sample bx of
// the row, one after the other. `out` gets every row's side by side; `begin`, unless null, each
// sample's first entry and the total at the end. A vector per row is freed once copied.
template <typename Rows, typename Count, typename Begin, typename Out>
void join_rows(const TraceGrid& grid, Rows& rows, const Count& count, Begin* begin, Out* out) {
  std::vector<std::uint32_t> row_start(static_cast<std::size_t>(grid.height) + 1, 0);
  for (int by = 0; by < grid.height; ++by)
    row_start[by + 1] = row_start[by] + static_cast<std::uint32_t>(row_size(rows, by));
  out->resize(row_start.back());
  if (begin) begin->resize(static_cast<std::size_t>(grid.width) * grid.height + 1);
  parallel_for_rows(grid.height, [&](int by) {
    if (begin) {
      std::uint32_t at = row_start[by];
      for (int bx = 0; bx < grid.width; ++bx) {
        (*begin)[static_cast<std::size_t>(by) * grid.width + bx] = at;
        at += static_cast<std::uint32_t>(count(by, bx));
      }
    }
    move_row(rows, by, out->begin() + row_start[by]);
  });
  if (begin) begin->back() = row_start.back();
}

// The same for entries beside others already joined (the same counts): without `begin`.
template <typename Rows, typename Out>
void join_rows(const TraceGrid& grid, Rows& rows, Out* out) {
  join_rows(
      grid, rows, [](int, int) { return 0; }, static_cast<std::vector<std::uint32_t>*>(nullptr),
      out);
}

}  // namespace ssgi::detail
