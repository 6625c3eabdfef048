// Pictures drawn by Debian's gnuplot (gnuplot-nox, which scripts/setup.sh installs): a well-kept
// plotting program driven by a short script, rather than a plotting library linked into the
// project. The data go in as tab-separated files beside the picture.
#pragma once

#include <string>

namespace retarget {

// Runs gnuplot on `script` (its text), which writes PNG files itself (set terminal pngcairo or
// png; set output). The script is kept beside the first output as <name>.gp for people to rerun
// and adapt. Throws retarget::Error when gnuplot is not installed ("gnuplot not found; scripts/
// setup.sh installs gnuplot-nox") or exits with an error (its message included).
void run_gnuplot(const std::string& script, const std::string& script_path);

// A string as a gnuplot string literal (double quotes, backslashes and quotes escaped).
std::string gnuplot_quote(const std::string& text);

}  // namespace retarget
