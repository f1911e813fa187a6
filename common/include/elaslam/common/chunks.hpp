// SPDX-License-Identifier: Apache-2.0
// Cutting a per-landmark message (a robot's snapshot, the global map) into chunks by
// landmark id so that each fits one datagram (contract::kMaxChunkBytes) and stands
// alone: chunk i covers the ids [id_begin, id_end), the chunks cover [0, max_id)
// without overlap, and a receiver can apply each chunk to its range whatever became of
// the others (lmap_snapshot_t, global_map_t). Two kinds of entry share the id space
// (static landmarks, moving ids), each with its own encoded size. No allocation when
// `out` has the capacity (max_chunks()).
#pragma once

#include <vector>

namespace elaslam {

struct ChunkSpan {
  int id_begin = 0, id_end = 0;  // landmark ids [id_begin, id_end)
  int first_a = 0, count_a = 0;  // entries of the first kind: a_ids[first_a, first_a + count_a)
  int first_b = 0, count_b = 0;  // entries of the second kind
};

struct ChunkSizes {
  int fixed_bytes = 0;  // an empty chunk, encoded (header, counts, fingerprint)
  int a_bytes = 1;      // one entry of the first kind
  int b_bytes = 1;      // one entry of the second kind
  int budget = 1200;    // at most this many bytes per chunk
  /// Entries of one kind that fit a chunk alone (>= 1 by construction of the budget).
  int per_chunk(int bytes) const { return (budget - fixed_bytes) / bytes; }
};

/// The most chunks `na` + `nb` entries can need (size `out` for it): every chunk but
/// the last was closed because the next entry did not fit, so it holds more than
/// room - (the larger entry) bytes.
inline int max_chunks(const ChunkSizes& s, int na, int nb) {
  const int room = s.budget - s.fixed_bytes;
  return 1 + (na * s.a_bytes + nb * s.b_bytes) / (room - (s.a_bytes > s.b_bytes ? s.a_bytes : s.b_bytes) + 1);
}

/// The sizes of a chunked message type Msg, measured on its generated encoder, and a
/// pool of `Msg` big enough for `max_a` + `max_b` entries, each chunk's arrays
/// reserved for a full chunk (filling a chunk then allocates nothing).
/// `grow_a(&msg, n)` / `grow_b(&msg, n)` give a message n entries of each kind
/// (arrays and count fields together).
template <class Msg, class GrowA, class GrowB>
void prepare_chunks(GrowA grow_a, GrowB grow_b, int budget, int max_a, int max_b, ChunkSizes* sizes,
                    std::vector<Msg>* pool) {
  Msg m{};
  sizes->budget = budget;
  sizes->fixed_bytes = m.getEncodedSize();
  grow_a(&m, 1);
  sizes->a_bytes = m.getEncodedSize() - sizes->fixed_bytes;
  grow_a(&m, 0);
  grow_b(&m, 1);
  sizes->b_bytes = m.getEncodedSize() - sizes->fixed_bytes;
  pool->resize(static_cast<std::size_t>(max_chunks(*sizes, max_a, max_b)));
  for (Msg& c : *pool) {  // a resize down keeps the capacity
    grow_a(&c, sizes->per_chunk(sizes->a_bytes));
    grow_a(&c, 0);
    grow_b(&c, sizes->per_chunk(sizes->b_bytes));
    grow_b(&c, 0);
  }
}

/// Cut [0, max_id) into chunks. `a_ids` (na of them) and `b_ids` (nb) are ascending,
/// within [0, max_id), and no id is in both. Every chunk holds at least one entry
/// unless there are none at all (then one empty chunk covers everything).
inline void cut_chunks(const int* a_ids, int na, const int* b_ids, int nb, const ChunkSizes& s, int max_id,
                       std::vector<ChunkSpan>* out) {
  out->clear();
  ChunkSpan c;
  int bytes = s.fixed_bytes, i = 0, j = 0;
  while (i < na || j < nb) {
    const bool take_a = j >= nb || (i < na && a_ids[i] < b_ids[j]);
    const int id = take_a ? a_ids[i] : b_ids[j];
    const int add = take_a ? s.a_bytes : s.b_bytes;
    if (bytes + add > s.budget && (c.count_a + c.count_b) > 0) {  // close the chunk before this entry
      c.id_end = id;
      out->push_back(c);
      c = ChunkSpan{id, 0, i, 0, j, 0};
      bytes = s.fixed_bytes;
    }
    bytes += add;
    if (take_a) ++i, ++c.count_a;
    else ++j, ++c.count_b;
  }
  c.id_end = max_id;
  out->push_back(c);
}

}  // namespace elaslam
