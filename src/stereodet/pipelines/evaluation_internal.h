// RunEvaluation's steps, shared with RunEvaluationMerge (eval_shard.cc). For the report module and
// its tests only.
#ifndef STEREODET_PIPELINES_EVALUATION_INTERNAL_H_
#define STEREODET_PIPELINES_EVALUATION_INTERNAL_H_

#include <filesystem>
#include <functional>
#include <optional>

#include "stereodet/pipelines/evaluation.h"
#include "stereodet/util/output_folder.h"

namespace stereodet {

// What results.json records about the input, from what LoadEvalFrames read.
EvalRunInfo MakeRunInfo(const EvalInputOptions& options, const EvalInput& input);

// RunEvaluation once the frames are read: evaluates every run on `input`, and with `out` writes
// the results folder into its staging folder, calls before_commit(staging, result) (which may
// write more files, or throw to leave nothing), and commits.
EvaluationResult EvaluateAndWrite(
    const EvaluationOptions& options, std::optional<StagedFolder>& out, EvalInput input,
    const std::function<void(const std::filesystem::path&, const EvaluationResult&)>&
        before_commit);

// The shard's files in `dir`: eval_shard.json and eval_frames.dat (RunEvaluation's header
// comment). Requires: `input` was read with keep_sources.
void WriteEvalShardFiles(const std::filesystem::path& dir, const EvalInputOptions& options,
                         const EvalInput& input);

}  // namespace stereodet

#endif  // STEREODET_PIPELINES_EVALUATION_INTERNAL_H_
