// Fuzzes the mesh file readers and intake: byte 0 picks the extension, the rest is the file.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "intake/intake.h"
#include "intake/read_mesh_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* extensions[] = {".obj", ".off", ".ply"};
  const std::string path = "/tmp/qgp_fuzz_" + std::to_string(getpid()) + extensions[data[0] % 3];
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data + 1, 1, size - 1, f);
  std::fclose(f);
  try {
    qgp::Progress progress;
    const qgp::PolygonSoup soup = qgp::read_mesh_file(path);
    if (soup.num_vertices() < 100000 && soup.face_vertices.size() < 400000)
      qgp::run_intake(soup, qgp::IntakeOptions{}, progress);
  } catch (const qgp::Error&) {
    // Refusing bad input with an Error is the expected outcome; anything else is a bug.
  }
  std::remove(path.c_str());
  return 0;
}
