// Shards: one of N parts of a list of frames, for running one command as N processes (on one
// machine or many) whose outputs never collide and whose union is the output of one run
// (docs/scale.md).
//
// Shard K of N (K = 0 .. N-1, written "K/N" on the command line) is the contiguous range
// [floor(K * n / N), floor((K + 1) * n / N)) of the command's frame list (sorted ids, or the split
// file's order). Contiguous rather than every N-th frame: a shard's files are neighbours on disk,
// an interrupted shard resumes from one point, the shards' outputs concatenated in shard order are
// the whole list in order (what `eval merge` relies on), and the shards' sizes differ by at most
// one frame.
#ifndef STEREODET_UTIL_SHARD_H_
#define STEREODET_UTIL_SHARD_H_

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace stereodet {

struct Shard {
  int index = 0;  // K, in 0 .. count-1
  int count = 1;  // N >= 1; 1 = the whole list (the default: no sharding)
  // True when the shard was named (ParseShard, `--shard K/N`), 0/1 included: the output is one
  // part of a sharded run and carries its shard record, so that `eval merge` / `detect merge` take
  // a run whose frames fit in one shard like any other (stereodet.scale with one task).
  bool named = false;

  // All the frames (count 1), named or not.
  bool Whole() const { return count == 1; }
  // The output must carry a shard record: a part of several, or a shard named on the command line.
  bool Recorded() const { return named || count != 1; }
  // Throws std::invalid_argument unless 1 <= count <= 1000000 and 0 <= index < count.
  void Check() const;
  // The first and one-past-the-last positions of this shard in a list of `n` items.
  size_t Begin(size_t n) const;
  size_t End(size_t n) const;
};

// "K/N". Name then Parse gives the shard back.
std::string ShardName(const Shard& shard);
// Parses "K/N" (decimal digits only, no spaces) into a shard with `named` set; nullopt for any
// other text or a shard that fails Check().
std::optional<Shard> ParseShard(std::string_view text);

}  // namespace stereodet

#endif  // STEREODET_UTIL_SHARD_H_
