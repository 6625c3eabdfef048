// retarget-infer: human face meshes -> avatar meshes through a retargeting bundle. The command
// line is infer/infer_command.h; the work is in infer/infer_run.h.
#include "infer/infer_command.h"

int main(int argc, char** argv) { return retarget::infer_command(argc, argv); }
