/* Quantized Retopo C API: the only interface the Blender add-on (ctypes) sees.
 *
 * Usage: create a session from arrays (or a file), set options and features, start a job on the
 * native worker thread, poll it (stage + fraction) until it is no longer running, then fetch the
 * results into caller-provided arrays and read the JSON report. Free the session at the end.
 *
 * Every function returns a qgp_status; on failure the message is available from
 * qgp_last_error() (any call, this thread) and, for session calls, qgp_session_error().
 * No function throws, aborts or exits. Poll, cancel and free are safe while a job runs; a cancel
 * takes effect within about a second. Array shapes are given at each declaration (row-major).
 */
#ifndef QGP_QGP_H
#define QGP_QGP_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32) && defined(QGP_BUILDING_LIBRARY)
#define QGP_API __declspec(dllexport) /* qgp.dll exports these and nothing else */
#elif defined(_WIN32)
#define QGP_API
#else
#define QGP_API __attribute__((visibility("default")))
#endif

typedef struct qgp_session qgp_session;

typedef enum qgp_status {
  QGP_OK = 0,
  QGP_ERR_INVALID_ARGUMENT = 1, /* malformed call: null pointer, bad option, wrong size */
  QGP_ERR_INVALID_MESH = 2,     /* the mesh is unusable (NaN, bad index, non-manifold, ...) */
  QGP_ERR_UNREADABLE_FILE = 3,  /* the file cannot be opened or parsed */
  /* 4 is not used (it was "stage not built yet"); the numbers of the others stay. */
  QGP_ERR_STAGE_FAILED = 5, /* a stage ran but produced no valid result */
  QGP_ERR_CANCELLED = 6,    /* the job was cancelled */
  QGP_ERR_BUSY = 7,         /* a job is running on this session */
  QGP_ERR_INTERNAL = 8,     /* unexpected internal error (a bug) */
  QGP_ERR_NOT_READY = 9     /* no result of that kind is available */
} qgp_status;

typedef enum qgp_job {
  QGP_JOB_INTAKE = 0, /* validate, repair, classify */
  QGP_JOB_REMESH = 1, /* the whole pipeline up to the quad mesh */
  QGP_JOB_GRID_UV = 2 /* the whole pipeline up to the integer-grid map */
} qgp_job;

typedef enum qgp_job_state {
  QGP_STATE_IDLE = 0,
  QGP_STATE_RUNNING = 1,
  QGP_STATE_DONE = 2,
  QGP_STATE_FAILED = 3,
  QGP_STATE_CANCELLED = 4
} qgp_job_state;

/* Library version, e.g. "0.1.0". */
QGP_API const char* qgp_version(void);

/* Message of the last failed call on the calling thread ("" if none). Valid until the next call. */
QGP_API const char* qgp_last_error(void);

/* vertices: num_vertices x 3 doubles; triangles: num_triangles x 3 vertex indices. The arrays
 * are copied. Validation happens in the intake job, so a bad mesh is reported there. */
QGP_API int qgp_session_create(const double* vertices, int64_t num_vertices, const int32_t* triangles,
                               int64_t num_triangles, qgp_session** out_session);

/* Reads an OBJ / PLY / OFF file into a new session. */
QGP_API int qgp_session_create_from_file(const char* path, qgp_session** out_session);

/* Cancels and joins a running job, then frees everything. Null is allowed. */
QGP_API void qgp_session_free(qgp_session* session);

/* Message of the last failed call or job on this session ("" if none). */
QGP_API const char* qgp_session_error(qgp_session* session);

/* Feature edges (e.g. Blender's marked-sharp edges): num_edges x 2 input vertex indices. */
QGP_API int qgp_session_set_features(qgp_session* session, const int32_t* edges, int64_t num_edges);

/* Painted density: one positive value per input vertex, the linear quad density asked there (2:
 * quads half as long; 1: the target; clamped to 1/16 .. 16); count 0 clears it. The quad count asked
 * stays the total. */
QGP_API int qgp_session_set_density(qgp_session* session, const double* values, int64_t count);

/* Numeric options: "target_faces", "edge_length", "sharp_angle" (degrees, < 0 = off), "adaptive"
 * (0 = uniform quads, default, to 1 = strongly curvature-adaptive: edge length following the radius
 * of curvature within 4x either way of the typical one),
 * "drop_bad_components" (0/1: drop the parts intake cannot repair instead of refusing the mesh),
 * "weld_tolerance" (>= 0, relative to the bounding-box diagonal, default 1e-6: boundary vertices
 * this close are merged; 0 = no welding), "refuse_non_manifold" (0/1: refuse non-manifold edges
 * instead of cutting them into sheets), "fallback_uv_map" (0/1: build the flip-free cell map where the
 * global map stays flipped, see qgp_result_uv_mesh_counts). A value <= 0 unsets target_faces /
 * edge_length. */
QGP_API int qgp_session_set_option(qgp_session* session, const char* name, double value);

/* String options: "quantizer" = "greedy" | "round"; "symmetry" = the mirror planes of the object's
 * own axes, "" (none, the default), "x", "xz", "xyz", ...: the positive half is remeshed with the
 * quad count divided among the copies, mirrored and welded on the planes (remesh jobs only; a grid-UV
 * job with symmetry fails with QGP_ERR_INVALID_ARGUMENT). The report's "symmetry" object counts the
 * faces cut and the vertices welded. */
QGP_API int qgp_session_set_option_string(qgp_session* session, const char* name, const char* value);

/* Starts a job (qgp_job) on the worker thread. QGP_ERR_BUSY if one is running. */
QGP_API int qgp_job_start(qgp_session* session, int job);

/* state: qgp_job_state; fraction: of the current stage, in [0,1]; stage: NUL-terminated stage
 * name copied into stage_buffer (truncated to stage_buffer_size). Any output may be null. */
QGP_API int qgp_job_poll(qgp_session* session, int* state, double* fraction, char* stage_buffer,
                         int64_t stage_buffer_size);

/* Requests cancellation of the running job (no-op when none runs). */
QGP_API int qgp_job_cancel(qgp_session* session);

/* Waits up to timeout_seconds (< 0: forever) for the job to end; state as in qgp_job_poll.
 * Returns the job's own status when it has ended (QGP_OK, or its error code). */
QGP_API int qgp_job_wait(qgp_session* session, double timeout_seconds, int* state);

/* The JSON report of the last job. Copies at most buffer_size bytes including the NUL into
 * buffer (which may be null); *needed receives the full size including the NUL. */
QGP_API int qgp_report_json(qgp_session* session, char* buffer, int64_t buffer_size, int64_t* needed);

/* The repaired mesh of the last intake: vertex and triangle counts, then the arrays
 * (vertices: nv x 3 doubles; triangles: nf x 3; component: nf component ids;
 *  input_vertex: nv input indices). Any array pointer may be null. With symmetry this is the
 * positive half: input_vertex is -1 for a vertex the cut made. */
QGP_API int qgp_intake_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_triangles,
                              int64_t* num_components);
QGP_API int qgp_intake_fetch(qgp_session* session, double* vertices, int32_t* triangles, int32_t* component,
                             int32_t* input_vertex);

/* The quad mesh of the last successful remesh job: counts, then vertices (nv x 3), quads
 * (nq x 4 vertex indices, counter-clockwise) and per quad the input face it lies on (nq).
 * QGP_ERR_NOT_READY when the last job produced no quad mesh. Any array may be null. */
QGP_API int qgp_result_quad_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_quads);
QGP_API int qgp_result_quad_fetch(qgp_session* session, double* vertices, int32_t* quads, int32_t* source_face);

/* The components of a many-part mesh that the last remesh job could not quad (the report's
 * "status" is "partial" and "failed_components" says why), kept as their repaired triangles, and
 * (a remesh with the greedy quantizer rescues every part whose layout gives no quads: quadded at a
 * finer density or by splitting its triangles, among the quads; the report's "rescued_components")
 * non-orientable parts, kept as their input triangles in their input orientation (numbered after
 * the components of qgp_intake_counts):
 * counts (0 and 0 when every component was quadded), then vertices (nv x 3), triangles (nt x 3),
 * per triangle its input face and its component (nt each). QGP_ERR_NOT_READY as for the quads. */
QGP_API int qgp_result_kept_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_triangles);
QGP_API int qgp_result_kept_fetch(qgp_session* session, double* vertices, int32_t* triangles, int32_t* source_face,
                                  int32_t* component);

/* The quad layout (T-mesh, the motorcycle graph) of the last successful remesh or grid-UV job, as
 * line segments over points on the surface (what `qgp remesh --layout-out` writes as polylines):
 * counts, then points (np x 3) and segments (ns x 2 point indices). Parts kept as triangles have
 * none. QGP_ERR_NOT_READY when the session has no current layout. Any array may be null. */
QGP_API int qgp_result_layout_counts(qgp_session* session, int64_t* num_points, int64_t* num_segments);
QGP_API int qgp_result_layout_fetch(qgp_session* session, double* points, int32_t* segments);

/* The integer-grid map of the last successful grid-UV or remesh job, per corner of the input
 * triangles: uv is num_triangles x 3 x 2 (1 unit = 1 quad; a triangle intake removed gets the map of
 * its nearest kept one at its corners; NaN on parts remeshed on a decimated working mesh and on
 * parts kept as triangles, see failed_components in the report);
 * cuts: the seam edges as input vertex pairs (num_cut_edges x 2). */
QGP_API int qgp_result_uv_counts(qgp_session* session, int64_t* num_cut_edges);
QGP_API int qgp_result_uv_fetch(qgp_session* session, double* uv, int32_t* cuts);

/* The integer-grid map as a triangle mesh of its own (last successful grid-UV or remesh job): the
 * repaired input, except that a component whose global map stayed flipped or wound and which got
 * the fallback cell map (option "fallback_uv_map" = 1 before the job) has the T-mesh inserted; that
 * map has no flipped triangle. Counts (refined_components: how many components are refined), then
 * vertices nv x 3, triangles nt x 3, uv nt x 3 x 2 (1 unit = 1 quad) and per triangle the input
 * face it lies in (nt; -1 if unknown). QGP_ERR_NOT_READY without a map. Any pointer may be null. */
QGP_API int qgp_result_uv_mesh_counts(qgp_session* session, int64_t* num_vertices, int64_t* num_triangles,
                                      int32_t* refined_components);
QGP_API int qgp_result_uv_mesh_fetch(qgp_session* session, double* vertices, int32_t* triangles, double* uv,
                                     int32_t* source_face);

/* Measures any polygon mesh (e.g. another remesher's output) against a reference triangle mesh
 * (repaired by intake first): vertices nv x 3, face_sizes nf, corners sum(face_sizes) indices;
 * ref_vertices nrv x 3, ref_triangles nrt x 3; sharp_angle_deg < 0 skips sharp-edge coverage.
 * The JSON (fields in docs/report.md, "measurements") is copied into json (json_size bytes incl.
 * the NUL); *needed gets its size; QGP_ERR_INVALID_ARGUMENT if the buffer is too small. */
QGP_API int qgp_measure_polygon_mesh(const double* vertices, int64_t num_vertices, const int32_t* face_sizes,
                                     int64_t num_faces, const int32_t* corners, const double* ref_vertices,
                                     int64_t num_ref_vertices, const int32_t* ref_triangles, int64_t num_ref_triangles,
                                     double sharp_angle_deg, char* json, int64_t json_size, int64_t* needed);

/* A texture atlas for a quad mesh (docs: every quad a K x K square of whole texels, charts packed into
 * a texture_width x texture_height texture with `gutter` texels between them, every seam a quarter
 * turn plus whole texels): vertices nv x 3, quads nq x 4 (counter-clockwise); texels_per_quad 0
 * chooses the largest that fits; mip_levels L keeps levels 1..L seam-free. corner_uv (8 nq doubles)
 * gets (u, v) in [0,1] per quad corner; info (may be null, 5 ints) gets charts, texels per quad,
 * seam edges, the gutter used and the texture use in millionths. QGP_ERR_INVALID_ARGUMENT (with the
 * sizes named) when the charts do not fit. */
QGP_API int qgp_atlas_quads(const double* vertices, int64_t num_vertices, const int32_t* quads, int64_t num_quads,
                            int texture_width, int texture_height, int texels_per_quad, int gutter, int mip_levels,
                            double* corner_uv, int32_t* info);

/* The same for polygons carrying an integer-grid map (e.g. Integer-Grid UVs' per-corner coordinates, 1
 * unit = 1 quad = K texels): faces face_sizes nf, corners sum(face_sizes) vertex indices (edges are
 * matched by them), grid_uv (u, v) per corner. Charts grow across sides continuous in the map without
 * overlapping; every seam maps texels onto texels. corner_uv gets (u, v) in [0,1] per corner, info as
 * above. */
QGP_API int qgp_atlas_polygons(const int32_t* face_sizes, int64_t num_faces, const int32_t* corners,
                               const double* grid_uv, int texture_width, int texture_height, int texels_per_quad,
                               int gutter, int mip_levels, double* corner_uv, int32_t* info);

/* Seam stitching of an image in a grid-aligned atlas (e.g. the one above): fills the empty texels
 * beside each seam from across it, so bilinear samples agree on both sides. Faces: face_sizes nf,
 * corners sum(face_sizes) vertex indices (edges are matched by them); corner_uv: (u, v) per corner.
 * pixels: width x height x channels floats, row 0 at v = 0 (Blender's order), changed in place
 * (only texels no face covers). info (may be null, 4 values): seam edges stitched, seam edges that
 * do not map texels onto texels (left as borders), texels stitched, charts. */
QGP_API int qgp_stitch_seams(const int32_t* face_sizes, int64_t num_faces, const int32_t* corners,
                             const double* corner_uv, float* pixels, int width, int height, int channels,
                             int64_t* info);

/* Reading a mesh file as it is (polygons, no repair), e.g. to import it into Blender. */
typedef struct qgp_soup qgp_soup;
QGP_API int qgp_soup_read(const char* path, qgp_soup** out_soup);
/* num_corners: total number of face corners (sum of face sizes). */
QGP_API int qgp_soup_counts(qgp_soup* soup, int64_t* num_vertices, int64_t* num_faces, int64_t* num_corners);
/* vertices: nv x 3; face_sizes: nf; corners: num_corners vertex indices, faces concatenated. */
QGP_API int qgp_soup_fetch(qgp_soup* soup, double* vertices, int32_t* face_sizes, int32_t* corners);
QGP_API void qgp_soup_free(qgp_soup* soup);

#ifdef __cplusplus
}
#endif

#endif /* QGP_QGP_H */
