#include "atlas/corner_faces.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <utility>

namespace qgp {

CornerFaces::CornerFaces(const PolygonSoup& faces, std::vector<CornerUv> corner_uv)
    : soup(faces), uv(std::move(corner_uv)), corner_face(faces.face_vertices.size()) {
  for (int f = 0; f < faces.num_faces(); ++f)
    for (int c = faces.face_start[f]; c < faces.face_start[f + 1]; ++c) corner_face[c] = f;
}

std::vector<int> sides_across(const CornerFaces& faces) {
  const auto& fv = faces.soup.face_vertices;
  auto key = [](int a, int b) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(std::min(a, b))) << 32) | static_cast<uint32_t>(std::max(a, b));
  };
  std::unordered_map<uint64_t, std::vector<int>> sides;
  for (size_t c = 0; c < fv.size(); ++c)
    sides[key(fv[c], fv[faces.next(static_cast<int>(c))])].push_back(static_cast<int>(c));
  std::vector<int> across(fv.size(), -1);
  for (const auto& [edge, list] : sides) {
    if (list.size() != 2 || fv[list[0]] != fv[faces.next(list[1])]) continue;
    across[list[0]] = list[1];
    across[list[1]] = list[0];
  }
  return across;
}

}  // namespace qgp
