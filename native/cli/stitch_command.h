// `qgp stitch ATLAS.obj IMAGE.png -o OUT.png`: seam stitching (atlas/stitch_seams.h) for a PNG image in the
// texture atlas of an OBJ mesh's per-corner vt.
#pragma once
#include <string>

namespace qgp::cli {

struct StitchCommand {
  std::string atlas, image, output, report;
};

// Runs the command; returns the exit status (0, 1: bad arguments or unwritable output, 2: unreadable input)
// after printing a summary, or the reason on stderr.
int run_stitch(const StitchCommand& command);

}  // namespace qgp::cli
