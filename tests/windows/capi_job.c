/* Loads the qgp library at run time, as the Blender add-on does (LoadLibrary on Windows, dlopen
 * elsewhere), and drives it through the C API alone: a remesh job on a generated torus (polled to
 * the end), the quads fetched and checked, then a mesh with a NaN coordinate (its intake must fail
 * with a message) and a cancelled job. Prints one line per check; the last line is
 * "quads <count> vertices <count>" (tests/windows/test_wine.py compares it between Windows and
 * Linux). Exit status 0 when every check passed.
 *   capi_job LIBRARY */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#define LOAD_LIBRARY(path) ((void*)LoadLibraryA(path))
#define LOAD_SYMBOL(library, name) ((void*)GetProcAddress((HMODULE)(library), name))
#else
#include <dlfcn.h>
#define LOAD_LIBRARY(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define LOAD_SYMBOL(library, name) dlsym(library, name)
#endif

#include "qgp/qgp.h"

#define RING 48
#define TUBE 24
#define QGP_FUNCTIONS(X)                                                                       \
  X(const char*, qgp_version, (void))                                                          \
  X(int, qgp_session_create, (const double*, int64_t, const int32_t*, int64_t, qgp_session**)) \
  X(void, qgp_session_free, (qgp_session*))                                                    \
  X(const char*, qgp_session_error, (qgp_session*))                                            \
  X(int, qgp_session_set_option, (qgp_session*, const char*, double))                          \
  X(int, qgp_job_start, (qgp_session*, int))                                                   \
  X(int, qgp_job_poll, (qgp_session*, int*, double*, char*, int64_t))                          \
  X(int, qgp_job_cancel, (qgp_session*))                                                       \
  X(int, qgp_job_wait, (qgp_session*, double, int*))                                           \
  X(int, qgp_result_quad_counts, (qgp_session*, int64_t*, int64_t*))                           \
  X(int, qgp_result_quad_fetch, (qgp_session*, double*, int32_t*, int32_t*))

#define DECLARE(ret, name, args) static ret(*p_##name) args;
QGP_FUNCTIONS(DECLARE)

static int failures = 0;
static void check(int ok, const char* what) {
  printf("%s: %s\n", ok ? "ok" : "FAILED", what);
  if (!ok) failures++;
}

static int load(const char* path) {
  void* library = LOAD_LIBRARY(path);
  if (!library) {
    printf("FAILED: cannot load %s\n", path);
    return 0;
  }
#define RESOLVE(ret, name, args)                            \
  *(void**)(&p_##name) = LOAD_SYMBOL(library, #name);       \
  if (!p_##name) {                                          \
    printf("FAILED: %s does not export " #name "\n", path); \
    return 0;                                               \
  }
  QGP_FUNCTIONS(RESOLVE)
  return 1;
}

/* A torus (ring radius 1, tube radius 0.35), RING x TUBE vertices, two triangles per grid cell. */
static void torus(double* vertices, int32_t* triangles) {
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < RING; i++) {
    for (int j = 0; j < TUBE; j++) {
      double u = 2 * pi * i / RING, v = 2 * pi * j / TUBE, r = 1 + 0.35 * cos(v);
      double* p = vertices + 3 * (i * TUBE + j);
      p[0] = r * cos(u), p[1] = r * sin(u), p[2] = 0.35 * sin(v);
      int a = i * TUBE + j, b = ((i + 1) % RING) * TUBE + j, c = ((i + 1) % RING) * TUBE + (j + 1) % TUBE,
          d = i * TUBE + (j + 1) % TUBE;
      int32_t* t = triangles + 6 * (i * TUBE + j);
      t[0] = a, t[1] = b, t[2] = c, t[3] = a, t[4] = c, t[5] = d;
    }
  }
}

/* Polls a running job to its end, as the add-on's modal operator does; returns the final state. */
static int poll_to_end(qgp_session* session) {
  int state = QGP_STATE_RUNNING, polls = 0;
  char stage[64];
  while (state == QGP_STATE_RUNNING) {
    p_qgp_job_wait(session, 0.05, &state);
    p_qgp_job_poll(session, &state, NULL, stage, sizeof stage);
    polls++;
  }
  check(polls > 0, "the job was polled to its end");
  return state;
}

static void remesh_torus(int64_t* num_quads, int64_t* num_vertices) {
  static double vertices[RING * TUBE * 3];
  static int32_t triangles[RING * TUBE * 6];
  torus(vertices, triangles);
  qgp_session* session = NULL;
  check(p_qgp_session_create(vertices, RING * TUBE, triangles, RING * TUBE * 2, &session) == QGP_OK && session,
        "session from arrays");
  check(p_qgp_session_set_option(session, "target_faces", 600) == QGP_OK, "option target_faces");
  check(p_qgp_job_start(session, QGP_JOB_REMESH) == QGP_OK, "remesh job started");
  check(poll_to_end(session) == QGP_STATE_DONE, "remesh job done");
  check(p_qgp_result_quad_counts(session, num_vertices, num_quads) == QGP_OK && *num_quads > 0, "quads made");
  double* quad_vertices = malloc(sizeof(double) * 3 * (size_t)(*num_vertices + 1));
  int32_t* quads = malloc(sizeof(int32_t) * 4 * (size_t)(*num_quads + 1));
  int32_t* source = malloc(sizeof(int32_t) * (size_t)(*num_quads + 1));
  check(p_qgp_result_quad_fetch(session, quad_vertices, quads, source) == QGP_OK, "quads fetched");
  int in_range = 1;
  for (int64_t q = 0; q < *num_quads; q++) {
    for (int k = 0; k < 4; k++) in_range &= quads[4 * q + k] >= 0 && quads[4 * q + k] < *num_vertices;
    in_range &= source[q] >= 0 && source[q] < RING * TUBE * 2;
  }
  check(in_range, "every quad corner and source face in range");
  /* A torus: V - E + F = 0 with E = 2F for a closed quad mesh, so V = F. */
  check(*num_vertices == *num_quads, "Euler characteristic of a torus (V = F)");
  free(quad_vertices), free(quads), free(source);
  p_qgp_session_free(session);
}

static void refuse_nan(void) {
  double vertices[9] = {0, 0, 0, 1, 0, 0, 0, NAN, 0};
  int32_t triangle[3] = {0, 1, 2};
  qgp_session* session = NULL;
  p_qgp_session_create(vertices, 3, triangle, 1, &session);
  int state = 0;
  p_qgp_job_start(session, QGP_JOB_INTAKE);
  int status = p_qgp_job_wait(session, -1, &state);
  const char* message = p_qgp_session_error(session);
  check(status == QGP_ERR_INVALID_MESH && state == QGP_STATE_FAILED && strstr(message, "NaN") != NULL,
        "a NaN coordinate is refused with a message naming it");
  printf("  (message: %s)\n", message);
  p_qgp_session_free(session);
}

static void cancel_job(void) {
  static double vertices[RING * TUBE * 3];
  static int32_t triangles[RING * TUBE * 6];
  torus(vertices, triangles);
  qgp_session* session = NULL;
  p_qgp_session_create(vertices, RING * TUBE, triangles, RING * TUBE * 2, &session);
  p_qgp_session_set_option(session, "target_faces", 20000);
  p_qgp_job_start(session, QGP_JOB_REMESH);
  check(p_qgp_job_cancel(session) == QGP_OK, "cancel accepted");
  int state = 0;
  p_qgp_job_wait(session, -1, &state);
  check(state == QGP_STATE_CANCELLED || state == QGP_STATE_DONE, "the cancelled job ended");
  p_qgp_session_free(session); /* joins the worker thread */
}

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: capi_job LIBRARY\n");
    return 2;
  }
  if (!load(argv[1])) return 1;
  printf("library version %s\n", p_qgp_version());
  int64_t num_quads = 0, num_vertices = 0;
  remesh_torus(&num_quads, &num_vertices);
  refuse_nan();
  cancel_job();
  printf("quads %lld vertices %lld\n", (long long)num_quads, (long long)num_vertices);
  return failures == 0 ? 0 : 1;
}
