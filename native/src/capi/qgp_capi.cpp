// C API implementation: a worker thread per job, every exception turned into a status code.
#include "qgp/qgp.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <thread>

#include "atlas/polygon_atlas.h"
#include "atlas/quad_atlas.h"
#include "atlas/stitch_seams.h"
#include "core/error.h"
#include "intake/read_mesh_file.h"
#include "metrics/polygon_metrics.h"
#include "pipeline/layout_lines.h"
#include "pipeline/session.h"
#include "pipeline/uv_mesh.h"

struct qgp_soup {
  qgp::PolygonSoup soup;
};

struct qgp_session {
  std::unique_ptr<qgp::Session> session;
  std::thread worker;
  std::atomic<bool> cancel{false};
  // Composed on the first request after a job (counts, then fetch); caller's thread, while idle.
  std::optional<qgp::UvMesh> uv_mesh;
  std::mutex mutex;  // guards everything below
  std::condition_variable finished;
  int state = QGP_STATE_IDLE;
  int job_status = QGP_OK;
  std::string stage;
  double fraction = 0;
  std::string error;
  std::string report_json = "{}";
};

namespace {

thread_local std::string t_last_error;
thread_local std::string t_session_error;

int status_of(qgp::ErrorCode code) { return static_cast<int>(code); }

int fail(qgp_session* s, int status, const std::string& message) {
  t_last_error = message;
  if (s) {
    std::lock_guard<std::mutex> lock(s->mutex);
    s->error = message;
  }
  return status;
}

// Runs fn, mapping every exception to a status code and message.
template <class Fn>
int guarded(qgp_session* s, Fn fn) noexcept {
  try {
    t_last_error.clear();
    return fn();
  } catch (const qgp::Error& e) {
    return fail(s, status_of(e.code()), e.what());
  } catch (const std::bad_alloc&) {
    return fail(s, QGP_ERR_INTERNAL, "out of memory");
  } catch (const std::exception& e) {
    return fail(s, QGP_ERR_INTERNAL, std::string("internal error: ") + e.what());
  } catch (...) {
    return fail(s, QGP_ERR_INTERNAL, "internal error: unknown exception");
  }
}

void require(bool condition, const std::string& message) {
  if (!condition) throw qgp::Error(qgp::ErrorCode::InvalidArgument, message);
}

bool is_running(qgp_session* s) {
  std::lock_guard<std::mutex> lock(s->mutex);
  return s->state == QGP_STATE_RUNNING;
}

void require_idle(qgp_session* s) {
  if (is_running(s)) throw qgp::Error(qgp::ErrorCode::Busy, "a job is running on this session");
}

void join_worker(qgp_session* s) {
  if (s->worker.joinable()) s->worker.join();
}

void run_job(qgp_session* s, qgp::Job job) {
  int status = QGP_OK;
  std::string message;
  qgp::Progress progress(
      [s](const std::string& stage, double fraction) {
        std::lock_guard<std::mutex> lock(s->mutex);
        s->stage = stage;
        s->fraction = fraction;
      },
      &s->cancel);
  try {
    s->session->run(job, progress);
  } catch (const qgp::Error& e) {
    status = status_of(e.code());
    message = e.what();
  } catch (const std::bad_alloc&) {
    status = QGP_ERR_INTERNAL;
    message = "out of memory";
  } catch (const std::exception& e) {
    status = QGP_ERR_INTERNAL;
    message = std::string("internal error: ") + e.what();
  } catch (...) {
    status = QGP_ERR_INTERNAL;
    message = "internal error: unknown exception";
  }
  std::string report;
  try {
    report = s->session->report().dump(2);
  } catch (...) {
    report = "{\"status\": \"error\"}";
  }
  std::lock_guard<std::mutex> lock(s->mutex);
  s->job_status = status;
  s->error = message;
  s->report_json = std::move(report);
  s->state = status == QGP_OK ? QGP_STATE_DONE : status == QGP_ERR_CANCELLED ? QGP_STATE_CANCELLED : QGP_STATE_FAILED;
  s->fraction = status == QGP_OK ? 1.0 : s->fraction;
  s->finished.notify_all();
}

}  // namespace

extern "C" {

const char* qgp_version(void) { return QGP_VERSION; }

const char* qgp_last_error(void) { return t_last_error.c_str(); }

int qgp_session_create(const double* vertices, int64_t num_vertices, const int32_t* triangles, int64_t num_triangles,
                       qgp_session** out_session) {
  return guarded(nullptr, [&] {
    require(out_session != nullptr, "out_session is null");
    *out_session = nullptr;
    require(num_vertices >= 0 && num_triangles >= 0, "counts must not be negative");
    require(num_vertices < std::numeric_limits<int32_t>::max() / 3 &&
                num_triangles < std::numeric_limits<int32_t>::max() / 3,
            "mesh too large (more than 700 million elements)");
    require(num_vertices == 0 || vertices != nullptr, "vertices is null");
    require(num_triangles == 0 || triangles != nullptr, "triangles is null");
    auto s = std::make_unique<qgp_session>();
    s->session = std::make_unique<qgp::Session>(
        qgp::soup_from_triangle_arrays(vertices, num_vertices, triangles, num_triangles));
    *out_session = s.release();
    return QGP_OK;
  });
}

int qgp_session_create_from_file(const char* path, qgp_session** out_session) {
  return guarded(nullptr, [&] {
    require(out_session != nullptr, "out_session is null");
    *out_session = nullptr;
    require(path != nullptr, "path is null");
    auto s = std::make_unique<qgp_session>();
    s->session = std::make_unique<qgp::Session>(qgp::read_mesh_file(path));
    *out_session = s.release();
    return QGP_OK;
  });
}

void qgp_session_free(qgp_session* session) {
  if (!session) return;
  session->cancel = true;
  join_worker(session);
  delete session;
}

const char* qgp_session_error(qgp_session* session) {
  if (!session) return "session is null";
  std::lock_guard<std::mutex> lock(session->mutex);
  t_session_error = session->error;
  return t_session_error.c_str();
}

int qgp_session_set_features(qgp_session* session, const int32_t* edges, int64_t num_edges) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require(num_edges >= 0, "num_edges is negative");
    require(num_edges == 0 || edges != nullptr, "edges is null");
    require_idle(session);
    qgp::RemeshOptions options = session->session->options();
    options.feature_edges.resize(static_cast<size_t>(num_edges));
    for (int64_t i = 0; i < num_edges; ++i) options.feature_edges[i] = {edges[2 * i], edges[2 * i + 1]};
    session->session->set_options(options);
    return QGP_OK;
  });
}

int qgp_session_set_density(qgp_session* session, const double* values, int64_t count) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require(count >= 0, "count is negative");
    require(count == 0 || values != nullptr, "values is null");
    require_idle(session);
    qgp::RemeshOptions options = session->session->options();
    options.density.assign(values, values + count);
    session->session->set_options(options);
    return QGP_OK;
  });
}

int qgp_session_set_option(qgp_session* session, const char* name, double value) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require(name != nullptr, "option name is null");
    require_idle(session);
    qgp::RemeshOptions options = session->session->options();
    const std::string key = name;
    if (key == "target_faces") {
      options.target_faces = value;
      if (value > 0) options.edge_length = 0;
    } else if (key == "edge_length") {
      options.edge_length = value;
      if (value > 0) options.target_faces = 0;
    } else if (key == "sharp_angle") {
      options.sharp_angle_deg = value;
    } else if (key == "drop_bad_components") {
      options.drop_bad_components = value != 0;
    } else if (key == "weld_tolerance") {
      options.weld_tolerance = value;
    } else if (key == "refuse_non_manifold") {
      options.refuse_non_manifold = value != 0;
    } else if (key == "adaptive") {
      options.adaptive = value;
    } else if (key == "fallback_uv_map") {
      options.fallback_uv_map = value != 0;
    } else {
      throw qgp::Error(qgp::ErrorCode::InvalidArgument, "unknown option '" + key +
                                                            "' (target_faces, edge_length, sharp_angle, "
                                                            "drop_bad_components, weld_tolerance, refuse_non_manifold, "
                                                            "fallback_uv_map, adaptive)");
    }
    session->session->set_options(options);
    return QGP_OK;
  });
}

int qgp_session_set_option_string(qgp_session* session, const char* name, const char* value) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require(name != nullptr && value != nullptr, "option name or value is null");
    require_idle(session);
    qgp::RemeshOptions options = session->session->options();
    if (std::string(name) == "quantizer") {
      options.quantizer = qgp::parse_quantizer(value);
    } else if (std::string(name) == "symmetry") {
      options.symmetry = qgp::parse_symmetry_axes(value);
    } else {
      throw qgp::Error(qgp::ErrorCode::InvalidArgument,
                       "unknown string option '" + std::string(name) + "' (quantizer, symmetry)");
    }
    session->session->set_options(options);
    return QGP_OK;
  });
}

int qgp_job_start(qgp_session* session, int job) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require(job == QGP_JOB_INTAKE || job == QGP_JOB_REMESH || job == QGP_JOB_GRID_UV,
            "unknown job " + std::to_string(job));
    require_idle(session);
    join_worker(session);
    {
      std::lock_guard<std::mutex> lock(session->mutex);
      session->state = QGP_STATE_RUNNING;
      session->job_status = QGP_OK;
      session->stage = "starting";
      session->fraction = 0;
      session->error.clear();
    }
    session->uv_mesh.reset();
    session->cancel = false;
    const qgp::Job kind = job == QGP_JOB_INTAKE   ? qgp::Job::Intake
                          : job == QGP_JOB_REMESH ? qgp::Job::Remesh
                                                  : qgp::Job::GridUV;
    try {
      session->worker = std::thread(run_job, session, kind);
    } catch (...) {
      std::lock_guard<std::mutex> lock(session->mutex);
      session->state = QGP_STATE_FAILED;
      throw;
    }
    return QGP_OK;
  });
}

int qgp_job_poll(qgp_session* session, int* state, double* fraction, char* stage_buffer, int64_t stage_buffer_size) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    std::lock_guard<std::mutex> lock(session->mutex);
    if (state) *state = session->state;
    if (fraction) *fraction = session->fraction;
    if (stage_buffer && stage_buffer_size > 0) {
      const size_t n = std::min<size_t>(session->stage.size(), static_cast<size_t>(stage_buffer_size - 1));
      std::memcpy(stage_buffer, session->stage.data(), n);
      stage_buffer[n] = '\0';
    }
    return QGP_OK;
  });
}

int qgp_job_cancel(qgp_session* session) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    session->cancel = true;
    return QGP_OK;
  });
}

int qgp_job_wait(qgp_session* session, double timeout_seconds, int* state) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    std::unique_lock<std::mutex> lock(session->mutex);
    auto done = [&] { return session->state != QGP_STATE_RUNNING; };
    if (timeout_seconds < 0) {
      session->finished.wait(lock, done);
    } else {
      session->finished.wait_for(lock, std::chrono::duration<double>(timeout_seconds), done);
    }
    if (state) *state = session->state;
    if (session->state == QGP_STATE_RUNNING) return static_cast<int>(QGP_OK);
    if (session->job_status != QGP_OK) t_last_error = session->error;
    return session->job_status;
  });
}

int qgp_report_json(qgp_session* session, char* buffer, int64_t buffer_size, int64_t* needed) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    std::lock_guard<std::mutex> lock(session->mutex);
    const std::string& json = session->report_json;
    if (needed) *needed = static_cast<int64_t>(json.size()) + 1;
    if (buffer && buffer_size > 0) {
      const size_t n = std::min<size_t>(json.size(), static_cast<size_t>(buffer_size - 1));
      std::memcpy(buffer, json.data(), n);
      buffer[n] = '\0';
    }
    return QGP_OK;
  });
}

int qgp_intake_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_triangles, int64_t* num_components) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::IntakeResult* intake = session->session->intake();
    if (!intake) throw qgp::Error(qgp::ErrorCode::InvalidArgument, "no intake result: run a job first");
    if (num_vertices) *num_vertices = intake->mesh.num_vertices();
    if (num_triangles) *num_triangles = intake->mesh.num_faces();
    if (num_components) *num_components = static_cast<int64_t>(intake->components.size());
    return QGP_OK;
  });
}

int qgp_intake_fetch(qgp_session* session, double* vertices, int32_t* triangles, int32_t* component,
                     int32_t* input_vertex) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::IntakeResult* intake = session->session->intake();
    if (!intake) throw qgp::Error(qgp::ErrorCode::InvalidArgument, "no intake result: run a job first");
    const qgp::TriMesh& mesh = intake->mesh;
    if (vertices) std::memcpy(vertices, mesh.V.data(), sizeof(double) * 3 * mesh.num_vertices());
    if (triangles) std::memcpy(triangles, mesh.F.data(), sizeof(int32_t) * 3 * mesh.num_faces());
    if (component)
      for (size_t c = 0; c < intake->components.size(); ++c)
        for (int f : intake->components[c].faces) component[f] = static_cast<int32_t>(c);
    if (input_vertex)
      for (size_t v = 0; v < intake->input_vertex.size(); ++v)
        input_vertex[v] = session->session->input_vertex_of(static_cast<int>(v));
    return QGP_OK;
  });
}

// The session's quad mesh; NotReady when the last job produced none.
static const qgp::QuadMesh& quad_result_of(qgp_session* session) {
  const qgp::QuadMesh* quads = session->session->quad_result();
  if (!quads) throw qgp::Error(qgp::ErrorCode::NotReady, "no quad mesh: run a remesh job first");
  return *quads;
}

int qgp_result_quad_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_quads) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::QuadMesh& quads = quad_result_of(session);
    if (num_vertices) *num_vertices = quads.V.rows();
    if (num_quads) *num_quads = quads.Q.rows();
    return QGP_OK;
  });
}

int qgp_result_quad_fetch(qgp_session* session, double* vertices, int32_t* quads, int32_t* source_face) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::QuadMesh* q = &quad_result_of(session);
    if (vertices) std::memcpy(vertices, q->V.data(), sizeof(double) * 3 * q->V.rows());
    if (quads) std::memcpy(quads, q->Q.data(), sizeof(int32_t) * 4 * q->Q.rows());
    if (source_face) {
      const auto& src = session->session->quad_source_face();
      for (int i = 0; i < q->Q.rows(); ++i) source_face[i] = i < static_cast<int>(src.size()) ? src[i] : -1;
    }
    return QGP_OK;
  });
}

int qgp_result_kept_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_triangles) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    quad_result_of(session);
    const qgp::TriMesh* kept = session->session->kept_triangles();
    if (num_vertices) *num_vertices = kept ? kept->num_vertices() : 0;
    if (num_triangles) *num_triangles = kept ? kept->num_faces() : 0;
    return QGP_OK;
  });
}

int qgp_result_kept_fetch(qgp_session* session, double* vertices, int32_t* triangles, int32_t* source_face,
                          int32_t* component) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    quad_result_of(session);
    const qgp::TriMesh* kept = session->session->kept_triangles();
    if (!kept) return QGP_OK;
    if (vertices) std::memcpy(vertices, kept->V.data(), sizeof(double) * 3 * kept->V.rows());
    if (triangles) std::memcpy(triangles, kept->F.data(), sizeof(int32_t) * 3 * kept->F.rows());
    const auto& src = session->session->kept_source_face();
    const auto& comp = session->session->kept_component();
    if (source_face) std::copy(src.begin(), src.end(), source_face);
    if (component) std::copy(comp.begin(), comp.end(), component);
    return QGP_OK;
  });
}

int qgp_result_layout_counts(qgp_session* session, int64_t* num_points, int64_t* num_segments) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::LayoutLines lines = qgp::compose_layout_lines(*session->session);
    if (num_points) *num_points = static_cast<int64_t>(lines.points.size());
    if (num_segments) *num_segments = static_cast<int64_t>(lines.segments.size());
    return QGP_OK;
  });
}

int qgp_result_layout_fetch(qgp_session* session, double* points, int32_t* segments) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::LayoutLines lines = qgp::compose_layout_lines(*session->session);
    if (points)
      for (const qgp::Vec3& p : lines.points) points = std::copy(p.data(), p.data() + 3, points);
    if (segments)
      for (const auto& s : lines.segments) segments = std::copy(s.begin(), s.end(), segments);
    return QGP_OK;
  });
}

int qgp_result_uv_counts(qgp_session* session, int64_t* num_cut_edges) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    if (session->session->corner_uv().empty())
      throw qgp::Error(qgp::ErrorCode::NotReady, "no grid UVs: run a grid-UV job first");
    if (num_cut_edges) *num_cut_edges = static_cast<int64_t>(session->session->cut_edges().size());
    return QGP_OK;
  });
}

int qgp_result_uv_fetch(qgp_session* session, double* uv, int32_t* cuts) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const std::vector<double>& corner_uv = session->session->corner_uv();
    if (corner_uv.empty()) throw qgp::Error(qgp::ErrorCode::NotReady, "no grid UVs: run a grid-UV job first");
    if (uv) std::copy(corner_uv.begin(), corner_uv.end(), uv);
    if (cuts)
      for (const auto& e : session->session->cut_edges()) {
        *cuts++ = e[0];
        *cuts++ = e[1];
      }
    return QGP_OK;
  });
}

}  // extern "C": the helpers below return C++ types

namespace {

const qgp::UvMesh& uv_mesh_of(qgp_session* session) {
  if (!session->uv_mesh) session->uv_mesh = qgp::compose_uv_mesh(*session->session, qgp::UvMapKind::IntegerGrid);
  return *session->uv_mesh;
}

}  // namespace

extern "C" {

int qgp_result_uv_mesh_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_triangles,
                              int32_t* refined_components) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::UvMesh& uv = uv_mesh_of(session);
    if (num_vertices) *num_vertices = uv.mesh.num_vertices();
    if (num_triangles) *num_triangles = uv.mesh.num_faces();
    if (refined_components) *refined_components = uv.refined_components;
    return QGP_OK;
  });
}

int qgp_result_uv_mesh_fetch(qgp_session* session, double* vertices, int32_t* triangles, double* uv,
                             int32_t* source_face) {
  return guarded(session, [&] {
    require(session != nullptr, "session is null");
    require_idle(session);
    const qgp::UvMesh& m = uv_mesh_of(session);
    if (vertices) std::memcpy(vertices, m.mesh.V.data(), sizeof(double) * 3 * m.mesh.V.rows());
    if (triangles) std::memcpy(triangles, m.mesh.F.data(), sizeof(int32_t) * 3 * m.mesh.F.rows());
    if (uv) std::memcpy(uv, m.uv.data(), sizeof(double) * 2 * m.uv.rows());
    if (source_face) std::copy(m.source_face.begin(), m.source_face.end(), source_face);
    return QGP_OK;
  });
}

}  // extern "C"

namespace {

// Polygons from flat arrays (vertices may be null: positions then stay zero), checked as they are read.
qgp::PolygonSoup polygon_arrays(const double* vertices, int64_t num_vertices, const int32_t* face_sizes,
                                int64_t num_faces, const int32_t* corners) {
  qgp::PolygonSoup mesh;
  mesh.positions.resize(static_cast<size_t>(num_vertices), qgp::Vec3::Zero());
  for (int64_t v = 0; vertices && v < num_vertices; ++v)
    mesh.positions[v] = qgp::Vec3(vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]);
  int64_t offset = 0;
  for (int64_t f = 0; f < num_faces; ++f) {
    require(face_sizes[f] >= 3, "face " + std::to_string(f) + " has fewer than three corners");
    for (int32_t k = 0; k < face_sizes[f]; ++k)
      require(corners[offset + k] >= 0 && corners[offset + k] < num_vertices,
              "face " + std::to_string(f) + " refers to a vertex out of range");
    mesh.add_face(corners + offset, face_sizes[f]);
    offset += face_sizes[f];
  }
  return mesh;
}

// Polygons given by their sizes and corners only (positions are not needed), and their per-corner coordinates.
std::pair<qgp::PolygonSoup, std::vector<qgp::CornerUv>> polygons_with_uv(const int32_t* face_sizes, int64_t num_faces,
                                                                         const int32_t* corners, const double* uv) {
  int64_t num_corners = 0;
  for (int64_t f = 0; f < num_faces; ++f) num_corners += std::max(face_sizes[f], 0);
  require(num_corners < INT32_MAX, "too many face corners");
  const int64_t num_vertices = num_corners > 0 ? int64_t{*std::max_element(corners, corners + num_corners)} + 1 : 0;
  std::vector<qgp::CornerUv> corner_uv(num_corners);
  for (int64_t c = 0; c < num_corners; ++c) corner_uv[c] = {uv[2 * c], uv[2 * c + 1]};
  return {polygon_arrays(nullptr, num_vertices, face_sizes, num_faces, corners), std::move(corner_uv)};
}

// An atlas's figures as the C API gives them: charts, texels per quad, seam edges, gutter, texture use (millionths).
void atlas_info(const qgp::AtlasFigures& atlas, int32_t* info) {
  if (!info) return;
  const int32_t values[5] = {atlas.num_charts, atlas.texels_per_quad, atlas.seam_edges, atlas.gutter,
                             static_cast<int32_t>(1e6 * atlas.texture_use)};
  std::copy_n(values, 5, info);
}

}  // namespace

extern "C" {

int qgp_atlas_quads(const double* vertices, int64_t num_vertices, const int32_t* quads, int64_t num_quads,
                    int texture_width, int texture_height, int texels_per_quad, int gutter, int mip_levels,
                    double* corner_uv, int32_t* info) {
  return guarded(nullptr, [&] {
    require(num_vertices >= 0 && num_quads >= 0 && num_quads < INT32_MAX / 4, "counts out of range");
    require((num_vertices == 0 || vertices) && (num_quads == 0 || quads) && corner_uv, "an array is null");
    qgp::QuadMesh mesh;
    mesh.V = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(vertices, num_vertices, 3);
    mesh.Q = Eigen::Map<const Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>>(quads, num_quads, 4);
    for (int64_t c = 0; c < 4 * num_quads; ++c)
      require(quads[c] >= 0 && quads[c] < num_vertices,
              "quad " + std::to_string(c / 4) + " refers to a vertex out of range");
    const qgp::QuadAtlas atlas = qgp::build_quad_atlas(
        mesh, qgp::AtlasOptions{texture_width, texture_height, texels_per_quad, gutter, mip_levels});
    std::copy_n(atlas.corner_uv.data(), atlas.corner_uv.size(), corner_uv);
    atlas_info(atlas, info);
    return QGP_OK;
  });
}

int qgp_atlas_polygons(const int32_t* face_sizes, int64_t num_faces, const int32_t* corners, const double* grid_uv,
                       int texture_width, int texture_height, int texels_per_quad, int gutter, int mip_levels,
                       double* corner_uv, int32_t* info) {
  return guarded(nullptr, [&] {
    require(num_faces >= 0, "counts out of range");
    require((num_faces == 0 || (face_sizes && corners && grid_uv)) && corner_uv, "an array is null");
    const auto [faces, uv] = polygons_with_uv(face_sizes, num_faces, corners, grid_uv);
    const qgp::PolygonAtlas atlas = qgp::build_polygon_atlas(
        faces, uv, qgp::AtlasOptions{texture_width, texture_height, texels_per_quad, gutter, mip_levels});
    for (size_t c = 0; c < uv.size(); ++c)
      corner_uv[2 * c] = atlas.corner_uv[c][0], corner_uv[2 * c + 1] = atlas.corner_uv[c][1];
    atlas_info(atlas, info);
    return QGP_OK;
  });
}

int qgp_stitch_seams(const int32_t* face_sizes, int64_t num_faces, const int32_t* corners, const double* corner_uv,
                     float* pixels, int width, int height, int channels, int64_t* info) {
  return guarded(nullptr, [&] {
    require(num_faces >= 0 && width > 0 && height > 0 && channels > 0 && channels <= 4, "sizes out of range");
    require((num_faces == 0 || (face_sizes && corners && corner_uv)) && pixels, "an array is null");
    const auto [faces, uv] = polygons_with_uv(face_sizes, num_faces, corners, corner_uv);
    qgp::AtlasImage image{width, height, channels, {}};
    const size_t size = static_cast<size_t>(width) * height * channels;
    image.texels.assign(pixels, pixels + size);
    const qgp::StitchReport report = qgp::stitch_seams(faces, uv, image);
    std::copy_n(image.texels.data(), size, pixels);
    if (info) {
      const int64_t values[4] = {report.seam_edges, report.unmatched_seam_edges, report.seam_texels, report.charts};
      std::copy_n(values, 4, info);
    }
    return QGP_OK;
  });
}

int qgp_measure_polygon_mesh(const double* vertices, int64_t num_vertices, const int32_t* face_sizes, int64_t num_faces,
                             const int32_t* corners, const double* ref_vertices, int64_t num_ref_vertices,
                             const int32_t* ref_triangles, int64_t num_ref_triangles, double sharp_angle_deg,
                             char* json, int64_t json_size, int64_t* needed) {
  return guarded(nullptr, [&] {
    require(num_vertices >= 0 && num_faces >= 0 && num_ref_vertices >= 0 && num_ref_triangles >= 0,
            "counts must not be negative");
    require((num_vertices == 0 || vertices) && (num_faces == 0 || (face_sizes && corners)) &&
                (num_ref_vertices == 0 || ref_vertices) && (num_ref_triangles == 0 || ref_triangles),
            "an array is null");
    const qgp::PolygonSoup mesh = polygon_arrays(vertices, num_vertices, face_sizes, num_faces, corners);
    qgp::Progress progress;
    const qgp::IntakeResult reference = qgp::run_intake(
        qgp::soup_from_triangle_arrays(ref_vertices, num_ref_vertices, ref_triangles, num_ref_triangles),
        qgp::IntakeOptions{}, progress);
    const std::string text =
        qgp::Json(qgp::measure_polygon_mesh(mesh, reference.mesh, sharp_angle_deg, progress)).dump();
    if (needed) *needed = static_cast<int64_t>(text.size()) + 1;
    require(json != nullptr && json_size > static_cast<int64_t>(text.size()),
            "json buffer too small: " + std::to_string(text.size() + 1) + " bytes needed");
    std::memcpy(json, text.c_str(), text.size() + 1);
    return QGP_OK;
  });
}

int qgp_soup_read(const char* path, qgp_soup** out_soup) {
  return guarded(nullptr, [&] {
    require(out_soup != nullptr, "out_soup is null");
    *out_soup = nullptr;
    require(path != nullptr, "path is null");
    auto soup = std::make_unique<qgp_soup>();
    soup->soup = qgp::read_mesh_file(path);
    *out_soup = soup.release();
    return QGP_OK;
  });
}

int qgp_soup_counts(qgp_soup* soup, int64_t* num_vertices, int64_t* num_faces, int64_t* num_corners) {
  return guarded(nullptr, [&] {
    require(soup != nullptr, "soup is null");
    if (num_vertices) *num_vertices = soup->soup.num_vertices();
    if (num_faces) *num_faces = soup->soup.num_faces();
    if (num_corners) *num_corners = static_cast<int64_t>(soup->soup.face_vertices.size());
    return QGP_OK;
  });
}

int qgp_soup_fetch(qgp_soup* soup, double* vertices, int32_t* face_sizes, int32_t* corners) {
  return guarded(nullptr, [&] {
    require(soup != nullptr, "soup is null");
    const qgp::PolygonSoup& s = soup->soup;
    if (vertices)
      for (int v = 0; v < s.num_vertices(); ++v)
        for (int k = 0; k < 3; ++k) vertices[3 * v + k] = s.positions[v][k];
    if (face_sizes)
      for (int f = 0; f < s.num_faces(); ++f) face_sizes[f] = s.face_size(f);
    if (corners) std::copy(s.face_vertices.begin(), s.face_vertices.end(), corners);
    return QGP_OK;
  });
}

void qgp_soup_free(qgp_soup* soup) { delete soup; }

}  // extern "C"
