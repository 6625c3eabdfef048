// Subcommands of `retarget`, one file each (train/<name>_command.cpp). argv[0] is the
// subcommand's name; each returns the process exit code and throws retarget::Error on bad input.
#pragma once

namespace retarget::cli {

int render_command(int argc, char** argv);      // cli/render_command.cpp
int synth_command(int argc, char** argv);       // cli/synth_command.cpp
int dataset_command(int argc, char** argv);     // cli/dataset_command.cpp
int train_command(int argc, char** argv);       // cli/train_command.cpp
int eval_command(int argc, char** argv);        // cli/eval_command.cpp
int eval_ladder(int argc, char** argv);         // cli/eval_ladder_command.cpp ("eval ladder")
int export_command(int argc, char** argv);      // cli/export_command.cpp
int correspond_command(int argc, char** argv);  // cli/correspond_command.cpp
int annotate_command(int argc, char** argv);    // cli/annotate_command.cpp
int annotate_serve(int argc, char** argv);      // cli/annotate_serve_command.cpp ("annotate serve")
int faces_command(int argc, char** argv);       // cli/faces_command.cpp
int rig_map_command(int argc, char** argv);     // cli/rig_map_command.cpp ("rig-map fit|apply")
int avatar_command(int argc, char** argv);      // cli/avatar_command.cpp ("avatar init", ...)
// cli/gltf_animation_command.cpp ("gltf-animation")
int gltf_animation_command(int argc, char** argv);
int avatar_meaning(int argc, char** argv);  // cli/avatar_meaning_command.cpp ("avatar meaning")
int avatar_landmarks(int argc, char** argv);
int pipeline_command(int argc, char** argv);  // cli/pipeline_command.cpp
int plot_command(int argc, char** argv);      // cli/plot_command.cpp

}  // namespace retarget::cli
