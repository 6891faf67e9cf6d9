// Reads OBJ, PLY (ascii / binary, faces or triangle strips) and OFF files into a polygon soup.
#pragma once
#include <string>

#include "intake/polygon_soup.h"

namespace qgp {

// Throws Error(UnreadableFile) with a message naming the problem (missing file, unknown
// extension, a format the readers cannot parse).
PolygonSoup read_mesh_file(const std::string& path);

}  // namespace qgp
