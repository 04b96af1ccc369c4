// `eval --shard` files and `eval merge` (pipelines/evaluation.h). Why the merge re-evaluates the
// shards' frame bytes instead of summing per-shard statistics: docs/scale.md ("What eval merge
// computes").
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "stereodet/pipelines/evaluation.h"
#include "stereodet/pipelines/evaluation_internal.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/run_manifest.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr char kShardFile[] = "eval_shard.json";
constexpr char kFramesFile[] = "eval_frames.dat";
constexpr char kFramesHeader[] = "stereodet eval frames 1\n";
// Format 2 records the frames file's hash (frames_fnv1a64), so a merge refuses an edited shard.
constexpr int kShardFormat = 2;

// eval_frames.dat: the header line, then per frame one line "ID HAS_DET N1 N2 N3 N4" and the
// N1 + N2 + N3 + N4 bytes of the label path, label text, detection path and detection text.
std::string FramesText(const std::vector<EvalFrameSource>& sources) {
  size_t size = sizeof(kFramesHeader);
  for (const EvalFrameSource& s : sources) {
    size += 64 + s.id.size() + s.label_path.size() + s.label_text.size() + s.det_path.size() +
            s.det_text.size();
  }
  std::string out;
  out.reserve(size);
  out += kFramesHeader;
  for (const EvalFrameSource& s : sources) {
    out += fmt::format("{} {} {} {} {} {}\n", s.id, s.has_detections ? 1 : 0, s.label_path.size(),
                       s.label_text.size(), s.det_path.size(), s.det_text.size());
    out += s.label_path;
    out += s.label_text;
    out += s.det_path;
    out += s.det_text;
  }
  return out;
}

std::vector<EvalFrameSource> ParseFrames(const std::string& text, const fs::path& path) {
  const std::string file = path.string();
  STEREODET_CHECK_IO(text.rfind(kFramesHeader, 0) == 0)
      << file << " is not an eval frames file (written by `stereodet eval --shard`)";
  std::vector<EvalFrameSource> out;
  size_t pos = sizeof(kFramesHeader) - 1;
  int line = 1;
  while (pos < text.size()) {
    ++line;
    const size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) throw ParseError(file, line, "frame", "truncated header");
    std::vector<std::string_view> fields;
    std::string_view rest(text.data() + pos, eol - pos);
    while (!rest.empty()) {
      const size_t sp = rest.find(' ');
      fields.push_back(rest.substr(0, sp));
      rest = sp == std::string_view::npos ? std::string_view() : rest.substr(sp + 1);
    }
    if (fields.size() != 6) throw ParseError(file, line, "frame", "expected 6 fields");
    size_t n[5] = {0, 0, 0, 0, 0};
    for (int k = 1; k < 6; ++k) {
      const auto [end, ec] =
          std::from_chars(fields[k].data(), fields[k].data() + fields[k].size(), n[k - 1]);
      if (ec != std::errc() || end != fields[k].data() + fields[k].size()) {
        throw ParseError(file, line, "frame", "bad number '" + std::string(fields[k]) + "'");
      }
    }
    pos = eol + 1;
    const size_t body = n[1] + n[2] + n[3] + n[4];
    if (n[0] > 1 || text.size() - pos < body) {
      throw ParseError(file, line, "frame", "truncated or bad frame " + std::string(fields[0]));
    }
    EvalFrameSource s;
    s.id = std::string(fields[0]);
    s.has_detections = n[0] == 1;
    s.label_path = text.substr(pos, n[1]);
    pos += n[1];
    s.label_text = text.substr(pos, n[2]);
    pos += n[2];
    s.det_path = text.substr(pos, n[3]);
    pos += n[3];
    s.det_text = text.substr(pos, n[4]);
    pos += n[4];
    out.push_back(std::move(s));
  }
  return out;
}

json ShardJson(const fs::path& dir) {
  const fs::path path = dir / kShardFile;
  STEREODET_CHECK_IO(fs::exists(path))
      << dir.string() << " is not an evaluation shard (no " << kShardFile
      << "; write one with `stereodet eval --shard K/N --out DIR`)";
  json j;
  try {
    j = json::parse(ReadFile(path));
  } catch (const json::exception& e) {
    throw ParseError(path.string(), 0, "json", e.what());
  }
  return j;
}

// results.json's "options" (num_threads aside) and "overlap_sets": what must agree for a merge.
json ComparedOptions(const fs::path& dir) {
  const fs::path path = dir / "results.json";
  json j;
  try {
    j = json::parse(ReadFile(path));
  } catch (const json::exception& e) {
    throw ParseError(path.string(), 0, "json", e.what());
  }
  if (!j.is_object() || (j.contains("options") && !j["options"].is_object()) ||
      (j.contains("overlap_sets") && !j["overlap_sets"].is_array())) {
    throw ParseError(path.string(), 0, "options",
                     "not a results.json of eval: expected an object with an \"options\" object");
  }
  json o = j.value("options", json::object());
  o.erase("num_threads");
  return {{"options", o}, {"overlap_sets", j.value("overlap_sets", json::array())}};
}

}  // namespace

void WriteEvalShardFiles(const fs::path& dir, const EvalInputOptions& options,
                         const EvalInput& input) {
  STEREODET_CHECK(input.sources.size() == input.frames.size())
      << "a shard's frames file needs the input read with keep_sources";
  const std::string frames = FramesText(input.sources);
  WriteFileAtomically(dir / kFramesFile, frames);
  json j;
  j["format"] = kShardFormat;
  j["frames_fnv1a64"] = HashHex(Fnv1a64(frames));
  j["shard"] = ShardName(options.shard);
  j["frames"] = input.frames.size();
  j["input"] = {
      {"gt", options.gt.string()},
      {"det", options.det.string()},
      {"split", options.split},
      {"lenient", options.lenient},
      {"score_if_missing", options.score_if_missing ? json(*options.score_if_missing) : json()}};
  j["ignored_files"] = input.ignored_files;
  j["det_run"] = input.det_run;
  j["det_not_from_run"] = input.det_not_from_run;
  WriteFileAtomically(dir / kShardFile, j.dump(2) + "\n");
}

EvalShardInfo ReadEvalShard(const fs::path& dir) {
  const json j = ShardJson(dir);
  const std::string file = (dir / kShardFile).string();
  EvalShardInfo info;
  // The field being read, so that a wrong type is reported as "field input.det: expected a
  // string, got {...}" rather than nlohmann's words alone.
  std::string field;
  auto at = [&](const json& parent, const std::string& name,
                const std::string& path) -> const json& {
    field = path;
    if (!parent.is_object()) {
      throw ParseError(file, 0, field, "expected an object holding '" + name + "'");
    }
    if (!parent.contains(name)) throw ParseError(file, 0, field, "missing");
    return parent.at(name);
  };
  auto expect = [&](const json& value, bool ok, const char* what) -> const json& {
    if (!ok)
      throw ParseError(file, 0, field,
                       std::string("expected ") + what + ", got " + value.dump().substr(0, 60));
    return value;
  };
  try {
    const json& format = at(j, "format", "format");
    expect(format, format.is_number_integer(), "an integer");
    STEREODET_CHECK_IO(format.get<int64_t>() == kShardFormat)
        << file << ": format " << format.dump() << ", this version reads " << kShardFormat;
    const json& shard_text = at(j, "shard", "shard");
    expect(shard_text, shard_text.is_string(), "a string K/N");
    const std::optional<Shard> shard = ParseShard(shard_text.get<std::string>());
    if (!shard) throw ParseError(file, 0, "shard", "not K/N: " + shard_text.dump());
    info.shard = *shard;
    const json& frames = at(j, "frames", "frames");
    expect(frames, frames.is_number_integer(), "an integer");
    info.frames = frames.get<int64_t>();
    const json& hash = at(j, "frames_fnv1a64", "frames_fnv1a64");
    info.frames_hash = expect(hash, hash.is_string(), "a string").get<std::string>();
    const json& in = at(j, "input", "input");
    for (const char* name : {"gt", "det", "split"}) {
      const json& v = at(in, name, std::string("input.") + name);
      expect(v, v.is_string(), "a string");
    }
    info.input.gt = in.at("gt").get<std::string>();
    info.input.det = in.at("det").get<std::string>();
    info.input.split = in.at("split").get<std::string>();
    const json& lenient = at(in, "lenient", "input.lenient");
    info.input.lenient = expect(lenient, lenient.is_boolean(), "true or false").get<bool>();
    // Absent in shards written before `--score` existed: unset.
    if (const auto it = in.find("score_if_missing"); it != in.end() && !it->is_null()) {
      field = "input.score_if_missing";
      info.input.score_if_missing = expect(*it, it->is_number(), "a number or null").get<double>();
    }
    info.input.shard = info.shard;
  } catch (const json::exception& e) {
    throw ParseError(file, 0, field, e.what());
  }
  return info;
}

void EvaluationMergeOptions::Check() const {
  STEREODET_CHECK(!shards.empty()) << "eval merge: no shard folder given";
  // The shards' options are checked against the merge's in the results folder (results.json).
  STEREODET_CHECK(!evaluation.out.empty()) << "eval merge needs an output folder (out)";
  EvaluationOptions e = evaluation;
  if (e.input.gt.empty()) e.input.gt = "-";  // the shards' input, filled by the merge
  if (e.input.det.empty()) e.input.det = "-";
  e.Check();
}

EvalInput LoadEvalShards(const std::vector<fs::path>& dirs, int num_threads,
                         EvalInputOptions* shards_input) {
  STEREODET_CHECK(!dirs.empty()) << "no eval shard folder given";
  std::vector<std::pair<EvalShardInfo, fs::path>> shards;
  for (const fs::path& dir : dirs) shards.emplace_back(ReadEvalShard(dir), dir);
  std::sort(shards.begin(), shards.end(),
            [](const auto& a, const auto& b) { return a.first.shard.index < b.first.shard.index; });
  const int n = shards.front().first.shard.count;
  const EvalInputOptions& first = shards.front().first.input;
  for (size_t k = 0; k < shards.size(); ++k) {
    const auto& [info, dir] = shards[k];
    STEREODET_CHECK(info.shard.count == n)
        << "eval shards: " << dir.string() << " is shard " << ShardName(info.shard) << ", but "
        << shards.front().second.string() << " is one of " << n;
    STEREODET_CHECK(info.shard.index >= static_cast<int>(k))
        << "eval shards: shard " << ShardName(info.shard) << " is given twice (at "
        << shards[k - 1].second.string() << " and " << dir.string() << ")";
    STEREODET_CHECK(info.shard.index == static_cast<int>(k))
        << "eval shards: shard " << k << "/" << n << " is missing (the next given is "
        << ShardName(info.shard) << ", at " << dir.string() << ")";
    STEREODET_CHECK(info.input.gt == first.gt && info.input.det == first.det &&
                    info.input.split == first.split && info.input.lenient == first.lenient &&
                    info.input.score_if_missing == first.score_if_missing)
        << "eval shards: " << dir.string() << " evaluated other input (--gt " << info.input.gt
        << " --det " << info.input.det << " --split '" << info.input.split << "') than "
        << shards.front().second.string();
  }
  STEREODET_CHECK(static_cast<int>(shards.size()) == n)
      << "eval shards: " << shards.size() << " shard folders for " << n << " shards; shard "
      << shards.size() << "/" << n << " is missing";

  std::vector<EvalFrameSource> sources;
  std::vector<std::string> det_not_from_run;
  for (const auto& [info, dir] : shards) {
    const std::string frames = ReadFile(dir / kFramesFile);
    STEREODET_CHECK_IO(HashHex(Fnv1a64(frames)) == info.frames_hash)
        << (dir / kFramesFile).string() << " is not the file its " << kShardFile
        << " records (hash " << HashHex(Fnv1a64(frames)) << ", recorded " << info.frames_hash
        << "); it changed since its shard ran: evaluate that shard again";
    std::vector<EvalFrameSource> part = ParseFrames(frames, dir / kFramesFile);
    STEREODET_CHECK_IO(static_cast<int64_t>(part.size()) == info.frames)
        << (dir / kFramesFile).string() << " holds " << part.size() << " frames, " << kShardFile
        << " says " << info.frames;
    std::move(part.begin(), part.end(), std::back_inserter(sources));
    const json j = ShardJson(dir);
    for (const json& f : j.at("det_not_from_run")) det_not_from_run.push_back(f.get<std::string>());
  }
  std::set<std::string> ids;
  for (const EvalFrameSource& s : sources) {
    STEREODET_CHECK_IO(ids.insert(s.id).second)
        << "eval shards: frame " << s.id << " is in more than one shard";
  }
  EvalInput input = EvalInputFromSources(std::move(sources), first.lenient, num_threads,
                                         /*keep_sources=*/false, first.score_if_missing);
  const json j0 = ShardJson(shards.front().second);
  input.ignored_files = j0.at("ignored_files").get<std::vector<std::string>>();
  input.det_run = j0.at("det_run").get<std::string>();
  input.det_not_from_run = std::move(det_not_from_run);
  if (shards_input != nullptr) *shards_input = first;
  return input;
}

EvaluationResult RunEvaluationMerge(const EvaluationMergeOptions& options) {
  options.Check();
  EvaluationOptions evaluation = options.evaluation;
  const int threads = evaluation.input.num_threads;
  EvalInputOptions first;
  EvalInput input = LoadEvalShards(options.shards, threads, &first);
  evaluation.input = first;
  evaluation.input.shard = Shard{};
  evaluation.input.num_threads = threads;
  evaluation.Check();
  std::vector<std::pair<std::string, fs::path>> inputs;
  for (const fs::path& dir : options.shards) inputs.emplace_back("shard", dir);
  if (!evaluation.out.empty()) CheckOutputDoesNotOverlapInputs("--out", evaluation.out, inputs);
  std::optional<StagedFolder> out;
  if (!evaluation.out.empty())
    out.emplace(evaluation.out, "eval merge", std::vector<std::string>{kMakerEval});

  return EvaluateAndWrite(
      evaluation, out, std::move(input), [&](const fs::path& staging, const EvaluationResult&) {
        const json merged = ComparedOptions(staging);
        for (const fs::path& dir : options.shards) {
          const json shard = ComparedOptions(dir);
          STEREODET_CHECK(shard == merged)
              << "eval merge: " << dir.string()
              << " was evaluated with other options than this merge's; give the merge the "
                 "shards' options. The shard's: "
              << shard.dump() << "; the merge's: " << merged.dump();
        }
      });
}

}  // namespace stereodet
