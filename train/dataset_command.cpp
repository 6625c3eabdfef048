#include "core/error.h"
#include "train/commands.h"

namespace retarget::cli {

int dataset_command(int, char**) { throw Error("retarget dataset", "not available in this build yet"); }

}  // namespace retarget::cli
