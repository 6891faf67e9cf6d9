// Fuzzes the C API array entry points: arbitrary vertices (NaN, huge, duplicates) and triangles
// (out of range, repeated, non-manifold) through a full intake job, and through the atlas calls.
#include <cstdint>
#include <cstring>
#include <vector>

#include "qgp/qgp.h"

// The stateless atlas calls on the same arrays: the triangles as faces with UVs from the vertex values, the
// index list as quads. Errors are expected; a crash, leak or sanitizer report is a finding.
void fuzz_atlas_calls(uint8_t flags, const std::vector<double>& vertices, int nv, const std::vector<int32_t>& indices) {
  const int64_t nf = static_cast<int64_t>(indices.size() / 3);
  std::vector<int32_t> sizes(nf, 3);
  std::vector<double> uv(6 * nf);
  for (size_t c = 0; c < uv.size(); ++c) uv[c] = vertices.empty() ? 0.5 : vertices[c % vertices.size()] / 16.0;
  std::vector<double> atlas_uv(6 * nf);
  int32_t polygon_info[5];
  qgp_atlas_polygons(sizes.data(), nf, indices.data(), uv.data(), 32, 32, 0, flags % 3, 0, atlas_uv.data(),
                     polygon_info);
  std::vector<float> pixels(8 * 8 * 3, 0.5f);
  qgp_stitch_seams(sizes.data(), nf, indices.data(), uv.data(), pixels.data(), 8, 8, 3, nullptr);
  const int64_t nq = static_cast<int64_t>(indices.size() / 4);
  std::vector<double> corner_uv(8 * nq);
  int32_t info[5];
  qgp_atlas_quads(vertices.data(), nv, indices.data(), nq, 16 + flags % 64, 16, 0, flags % 4, (flags >> 2) % 3,
                  corner_uv.data(), info);
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const int nv = data[0] % 32, raw_index_range = nv + 2;
  size_t pos = 2;
  const bool raw_doubles = data[1] & 1;
  std::vector<double> vertices;
  for (int i = 0; i < 3 * nv; ++i) {
    if (raw_doubles && pos + 8 <= size) {
      double d;
      std::memcpy(&d, data + pos, 8);
      vertices.push_back(d);
      pos += 8;
    } else {
      vertices.push_back(pos < size ? static_cast<double>(static_cast<int8_t>(data[pos++])) : 0.0);
    }
  }
  std::vector<int32_t> triangles;
  while (pos + 3 <= size) {
    for (int k = 0; k < 3; ++k) triangles.push_back(static_cast<int32_t>(data[pos++] % raw_index_range) - 1);
  }
  fuzz_atlas_calls(data[1], vertices, nv, triangles);
  qgp_session* s = nullptr;
  if (qgp_session_create(vertices.data(), nv, triangles.data(), static_cast<int64_t>(triangles.size() / 3), &s) !=
      QGP_OK)
    return 0;
  if (data[1] & 2) qgp_session_set_option(s, "drop_bad_components", 1);
  if (qgp_job_start(s, QGP_JOB_INTAKE) == QGP_OK) {
    int state = 0;
    qgp_job_wait(s, -1, &state);
    int64_t nvo = 0, nfo = 0, nco = 0;
    if (qgp_intake_counts(s, &nvo, &nfo, &nco) == QGP_OK) {
      std::vector<double> v(3 * nvo);
      std::vector<int32_t> f(3 * nfo), c(nfo), iv(nvo);
      qgp_intake_fetch(s, v.data(), f.data(), c.data(), iv.data());
    }
    int64_t needed = 0;
    qgp_report_json(s, nullptr, 0, &needed);
  }
  qgp_session_free(s);
  return 0;
}
