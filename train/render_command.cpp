#include "core/error.h"
#include "train/commands.h"

namespace retarget::cli {

int render_command(int, char**) { throw Error("retarget render", "not available in this build yet"); }

}  // namespace retarget::cli
