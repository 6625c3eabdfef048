// The stages of `retarget pipeline` for a recipe, in order (pipeline/stage.h): the data (synth,
// avatar init, datasets, extras), the VAEs, the proposed controller table and the test faces
// (pipeline/data_stages.cpp), then the method on its budget: rounds of comparisons, the
// translation network, bundles, the rig head, inference on the test faces, the evaluation and
// the error ladder (pipeline/method_stages.cpp). Paths: pipeline/run_layout.h.
#pragma once

#include <string>
#include <vector>

#include "pipeline/recipe.h"
#include "pipeline/run_layout.h"
#include "pipeline/stage.h"

namespace retarget {

std::vector<Stage> pipeline_stages(const Recipe& recipe, const std::string& run);

// The two halves, each appending to `stages` (keys of earlier stages may appear in `after`).
void add_data_stages(const Recipe& recipe, const RunLayout& layout, std::vector<Stage>& stages);
void add_method_stages(const Recipe& recipe, const RunLayout& layout, std::vector<Stage>& stages);

// After the rounds (pipeline/method_results.cpp): the translation network on the last round's
// groups and triplets, its bundles, the rig head on every round's answers, the zero-annotation
// map, every method on the test faces, the evaluation per set and the error ladder.
// `projects`: the rounds' annotation projects, in order (stage keys prefix + "round-NN").
void add_method_results(const Recipe& recipe, const RunLayout& layout, const std::string& prefix,
                        const std::vector<std::string>& projects, int last_round, std::vector<Stage>& stages);

// Helpers the halves share.
StageCommand retarget_command(std::vector<std::string> args);
StageCommand infer_command_line(std::vector<std::string> args);
// Where a stage's rig and face model come from: stages to run after, or files to digest.
void depend_on_rig(const Recipe& recipe, const RunLayout& layout, Stage& stage);
void depend_on_face_model(const Recipe& recipe, const RunLayout& layout, Stage& stage);
// The controller table: a synthetic rig's is made by the synth stage, any other is digested.
void depend_on_table(const Recipe& recipe, const RunLayout& layout, Stage& stage);
// A training stage: `retarget train CONFIG --set ... --out FOLDER --force`, then `then`. Its
// resume continues the run in FOLDER (`train FOLDER --resume`), or skips the training when the
// run finished before the kill, then runs `then`. processes > 1: both train commands get
// `--nproc processes` (data-parallel workers).
Stage training_stage(const std::string& key, const std::string& title, const std::string& config,
                     const std::vector<std::string>& sets, const std::string& folder,
                     const std::vector<StageCommand>& then, int processes = 1);

}  // namespace retarget
