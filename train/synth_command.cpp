#include "core/error.h"
#include "train/commands.h"

namespace retarget::cli {

int synth_command(int, char**) { throw Error("retarget synth", "not available in this build yet"); }

}  // namespace retarget::cli
