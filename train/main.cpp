// retarget: the training-side command line. Each subcommand lives in train/cli.cpp.
#include "train/cli.h"

int main(int argc, char** argv) { return retarget::cli::run(argc, argv); }
