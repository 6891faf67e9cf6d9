// qgp: command-line front end of the native pipeline, for batch use and tests.
//
// Exit codes: 0 success (parts rescued with more quads are named on stderr, report:
// rescued_components), 1 bad command line (or an output that cannot be written), 2 unusable
// input (with a one-line reason on stderr), 3 a pipeline stage failed or was cancelled, 4 internal
// error (also when the process is ended from inside a library, e.g. MUMPS calling exit, or by a
// fatal signal: see report_abnormal_ends), 5 complete except named parts: a component of a many-part
// mesh (a non-orientable one) could not be quadded and is written as its triangles (report:
// failed_components).
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "atlas/polygon_atlas.h"
#include "atlas/quad_atlas.h"
#include "core/error.h"
#include "core/json.h"
#include "intake/read_mesh_file.h"
#include "mesh_writers.h"
#include "pipeline/layout_lines.h"
#include "pipeline/session.h"
#include "pipeline/uv_mesh.h"
#include "stitch_command.h"
#include "tmesh/tmesh_system.h"

namespace {

// --- Abnormal ends: a library under the pipeline (MUMPS: "** MPI_ABORT called", then a Fortran
// STOP, i.e. exit(0)) or a fatal signal must never look like success to a batch script.
std::atomic<bool> g_pipeline_running{false};

void write_stderr(const char* text) {
  ssize_t ignored = write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

void exit_during_pipeline() {
  if (!g_pipeline_running.load()) return;
  write_stderr(
      "qgp: internal error: a library under the pipeline ended the process (its message, if any, is "
      "above); no output was written\n");
  _exit(4);
}

// Sets g_pipeline_running for the lifetime of a pipeline run (also when it throws).
struct PipelineRunning {
  PipelineRunning() { g_pipeline_running = true; }
  ~PipelineRunning() { g_pipeline_running = false; }
};

void fatal_signal(int sig) {
  const char* what = sig == SIGSEGV   ? "crashed (SIGSEGV)"
                     : sig == SIGABRT ? "aborted (SIGABRT)"
                     : sig == SIGFPE  ? "crashed (SIGFPE)"
                                      : "crashed (SIGBUS)";
  write_stderr("qgp: internal error: ");
  write_stderr(what);
  write_stderr("; no output was written\n");
  signal(sig, SIG_DFL);
  raise(sig);
}

void report_abnormal_ends() {
  std::atexit(exit_during_pipeline);
#ifdef _WIN32
  for (int sig : {SIGSEGV, SIGABRT, SIGFPE}) signal(sig, fatal_signal);  // Windows has no SIGBUS, no sigaction
#else
  struct sigaction action {};
  action.sa_handler = fatal_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (int sig : {SIGSEGV, SIGABRT, SIGBUS, SIGFPE}) sigaction(sig, &action, nullptr);
#endif
}

struct CommandLine {
  std::string command, input, output, report, features, uv_out, layout_out, density, atlas_out, uv_atlas_out;
  int texture_size = 1024;
  qgp::AtlasOptions atlas;
  std::string quantizer = "greedy", symmetry;
  bool no_weld = false;
  qgp::RemeshOptions options;
  qgp::cli::StitchCommand stitch;
};

void add_stitch_command(CLI::App& app, qgp::cli::StitchCommand& stitch) {
  CLI::App* command = app.add_subcommand(
      "stitch", "Fill the gutters of an image in a texture atlas from across each seam, so seams do not show");
  command->add_option("ATLAS", stitch.atlas, "the mesh with its atlas as per-corner vt (.obj, e.g. from --atlas-out)")
      ->required();
  command->add_option("IMAGE", stitch.image, "the image in that atlas (.png, baked or painted)")->required();
  command->add_option("-o,--output", stitch.output, "the stitched image to write (.png)")->required();
  command->add_option("--report", stitch.report, "write a JSON report here");
}

// The `info` and `remesh` commands and their options (CLI11); --help on each describes them.
void add_commands(CLI::App& app, CommandLine& cl) {
  app.require_subcommand(1);
  CLI::App* info = app.add_subcommand("info", "Read, validate and repair a mesh; print what was found");
  CLI::App* remesh = app.add_subcommand("remesh", "Turn a triangle mesh into a pure-quad mesh");
  add_stitch_command(app, cl.stitch);
  for (CLI::App* command : {info, remesh}) {
    command->add_option("IN", cl.input, "input mesh: .obj, .ply or .off")->required();
    command->add_option("--report", cl.report, "write the JSON report here (also when the run fails)");
    command->add_flag("--drop-bad-components", cl.options.drop_bad_components,
                      "drop the parts that cannot be repaired (non-orientable ones; non-manifold ones with "
                      "--refuse-non-manifold) instead of refusing the mesh");
    command->add_flag("--no-weld", cl.no_weld,
                      "do not weld boundary vertices closer than 1e-6 of the bounding-box diagonal (by default "
                      "they are merged: meshes split at UV seams or hard normals become one surface again)");
    command->add_flag("--refuse-non-manifold", cl.options.refuse_non_manifold,
                      "refuse a mesh with non-manifold edges (more than two faces on an edge) instead of "
                      "cutting them apart into sheets whose cut edges become boundaries");
  }
  remesh->add_option("-o,--output", cl.output, "the quad mesh to write (.obj)")->required();
  CLI::Option* faces = remesh->add_option("--faces", cl.options.target_faces, "target quad count (default 2000)")
                           ->check(CLI::NonNegativeNumber);
  remesh->add_option("--edge-length", cl.options.edge_length, "target quad edge length, in model units")
      ->check(CLI::NonNegativeNumber)
      ->excludes(faces);
  remesh
      ->add_option("--sharp-angle", cl.options.sharp_angle_deg,
                   "keep edges whose faces meet at more than DEG degrees as feature curves")
      ->check(CLI::Range(0.0, 180.0));
  remesh->add_option("--features", cl.features, "feature edges: a file with one 0-based vertex-index pair per line");
  remesh
      ->add_option("--adaptive", cl.options.adaptive,
                   "curvature-adaptive quad size, 0 (uniform, default) to 1 (edge length follows the radius of "
                   "curvature, within 4x either way)")
      ->check(CLI::Range(0.0, 1.0));
  remesh->add_option("--density", cl.density,
                     "painted density: a file with one positive number per input vertex (one per line, in the "
                     "file's vertex order): the linear quad density there (2: quads half as long)");
  CLI::Option* uv_out =
      remesh->add_option("--uv-out", cl.uv_out, "write the integer-grid map as per-corner vt of an .obj");
  remesh->add_option("--atlas-out", cl.atlas_out,
                     "write the quad mesh again with a texture atlas as per-corner vt in [0,1]: every quad a square of "
                     "whole texels, charts packed without overlap, every seam a 90-degree turn plus whole texels");
  CLI::Option* uv_atlas_out = remesh->add_option(
      "--uv-atlas-out", cl.uv_atlas_out,
      "write the integer-grid map's triangles (as --uv-out) with a texture atlas of them as per-corner "
      "vt in [0,1]: charts cut along triangle edges, packed without overlap, every seam a 90-degree "
      "turn plus whole texels (--texture-size and the other atlas options apply)");
  remesh->add_option("--texture-size", cl.texture_size, "the atlas texture's width and height in texels (default 1024)")
      ->check(CLI::Range(1, 65536));
  remesh
      ->add_option("--texels-per-quad", cl.atlas.texels_per_quad,
                   "texels along a quad's side in the atlas (default: the most for which every chart fits)")
      ->check(CLI::Range(1, 65536));
  remesh->add_option("--gutter", cl.atlas.gutter, "empty texels between atlas charts (default 2)")
      ->check(CLI::Range(0, 1024));
  remesh
      ->add_option("--mip-levels", cl.atlas.mip_levels,
                   "keep the atlas seam-free at mip levels 1 to L too: texels per quad a power of two of at least "
                   "2^L, charts at multiples of 2^L texels, a gutter of at least 2^(L+1) (default 0)")
      ->check(CLI::Range(0, 8));
  remesh->add_option("--layout-out", cl.layout_out,
                     "write the T-mesh (motorcycle graph) as .obj polylines (with --symmetry: the positive half's)");
  remesh
      ->add_option("--symmetry", cl.symmetry,
                   "mirror-symmetric quads about the model's planes x = 0, y = 0, z = 0: x, y, z or a combination "
                   "(xz); the positive side is remeshed and mirrored")
      ->check([](const std::string& axes) {
        try {
          qgp::parse_symmetry_axes(axes);
          return std::string();
        } catch (const qgp::Error& e) {
          return std::string(e.what());
        }
      })
      ->excludes(uv_out)
      ->excludes(uv_atlas_out);
  remesh
      ->add_option("--quantizer", cl.quantizer, "greedy (the paper's, default) or round (the direct-rounding baseline)")
      ->check(CLI::IsMember({"greedy", "round"}));
}

// Parses the command line. On --help, or on a malformed command line (exit code 1, with the reason
// and the usage on stderr), returns false and sets *exit_code.
bool parse(int argc, char** argv, CommandLine* cl, int* exit_code) {
  CLI::App app("qgp: quad meshes and integer-grid maps from triangle meshes (Quantized Global Parametrization)", "qgp");
  app.allow_windows_style_options(false);  // on Windows too: /path/to/mesh.obj is a path, not an option
  add_commands(app, *cl);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) {
      *exit_code = app.exit(e);  // --help
      return false;
    }
    std::cerr << "qgp: " << e.what() << "\n" << app.help();
    *exit_code = 1;
    return false;
  }
  cl->command = app.got_subcommand("info") ? "info" : app.got_subcommand("stitch") ? "stitch" : "remesh";
  cl->options.quantizer = qgp::parse_quantizer(cl->quantizer);
  cl->options.symmetry = qgp::parse_symmetry_axes(cl->symmetry);
  if (cl->no_weld) cl->options.weld_tolerance = 0;
  return true;
}

// --density: one number per non-blank line ('#' starts a comment).
std::vector<double> read_density(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw qgp::Error(qgp::ErrorCode::UnreadableFile, "cannot read density file '" + path + "'");
  std::vector<double> values;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    double value;
    std::string rest;
    if (!(ls >> value)) {
      if (ls.eof() && line.find_first_not_of(" \t\r") == std::string::npos) continue;  // blank
      throw qgp::Error(qgp::ErrorCode::InvalidArgument,
                       "density file '" + path + "' line " + std::to_string(line_no) + ": expected a number");
    }
    if (ls >> rest)
      throw qgp::Error(qgp::ErrorCode::InvalidArgument,
                       "density file '" + path + "' line " + std::to_string(line_no) + ": one number per line");
    values.push_back(value);
  }
  return values;
}

std::vector<std::array<int, 2>> read_feature_pairs(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw qgp::Error(qgp::ErrorCode::UnreadableFile, "cannot read features file '" + path + "'");
  std::vector<std::array<int, 2>> pairs;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    long long a, b;
    if (!(ls >> a)) continue;  // blank or comment line
    std::string rest;
    if (!(ls >> b) || (ls >> rest) || a < 0 || b < 0 || a > INT32_MAX || b > INT32_MAX)
      throw qgp::Error(qgp::ErrorCode::InvalidArgument, "features file '" + path + "' line " + std::to_string(line_no) +
                                                            ": expected two vertex indices");
    pairs.push_back({static_cast<int>(a), static_cast<int>(b)});
  }
  return pairs;
}

// Writes the report to `path` (none if empty); false if it cannot be written.
bool write_report(const std::string& path, const qgp::Json& report) {
  if (path.empty()) return true;
  std::ofstream out(path);
  if (out) out << report.dump(2) << "\n";
  if (out) return true;
  std::cerr << "qgp: cannot write report '" << path << "'\n";
  return false;
}

void print_intake_summary(const qgp::Json& report) {
  if (!report.contains("input")) return;
  const qgp::Json& in = report["input"];
  std::cout << "vertices " << in["vertices"] << ", faces " << in["faces"] << " (input " << in["input_vertices"] << " / "
            << in["input_faces"] << ")\n";
  std::cout << "components " << in["components"] << ", genus " << in["genus"].dump() << ", boundary loops "
            << in["boundary_loops"].dump() << "\n";
  for (const auto& r : in["repairs"])
    std::cout << "repair " << r["kind"].get<std::string>() << ": " << r["count"] << "\n";
  for (const auto& w : in["warnings"]) std::cout << "warning: " << w.get<std::string>() << "\n";
}

int exit_code_for(qgp::ErrorCode code) {
  switch (code) {
    case qgp::ErrorCode::InvalidMesh:
    case qgp::ErrorCode::UnreadableFile: return 2;
    case qgp::ErrorCode::InvalidArgument: return 1;
    case qgp::ErrorCode::StageFailed:
    case qgp::ErrorCode::Cancelled: return 3;
    default: return 4;
  }
}

const qgp::ComponentState& first_quadded(const qgp::Session& session) {
  for (const auto& c : session.components())
    if (!c.failure) return c;
  return session.components().front();
}

// --uv-out: the map as its own mesh (pipeline/uv_mesh.h): the integer-grid map when every
// component has one, else the continuous seamless map.
void write_uv_output(const std::string& path, const qgp::Session& session, qgp::UvMapKind kind) {
  const qgp::UvMesh out = qgp::compose_uv_mesh(session, kind);
  std::ostringstream header;
  if (kind == qgp::UvMapKind::IntegerGrid)
    header << "qgp integer-grid map: per-corner vt, 1 uv unit = 1 quad";
  else
    header << "qgp seamless map (continuous, before quantization): per-corner vt, 1 uv unit = "
           << first_quadded(session).seamless_edge_length() << " model units";
  qgp::cli::write_obj(path, out.mesh, &out.uv, header.str());
}

// --layout-out: the T-mesh (motorcycle graph) of every component (but those kept as triangles) as
// OBJ polylines (when qgp::has_layout).
void write_layout_output(const std::string& path, const qgp::Session& session) {
  std::vector<const qgp::TriMesh*> meshes;
  std::vector<const qgp::TMesh*> tmeshes;
  for (const auto& c : session.components()) {
    if (c.failure) continue;
    meshes.push_back(&c.mesh);
    tmeshes.push_back(&c.traced->tmesh);
  }
  qgp::write_layout_obj(path, meshes, tmeshes);
}

void print_atlas_summary(const char* label, const qgp::AtlasFigures& atlas) {
  std::cout << label << ": " << atlas.num_charts << " charts, " << atlas.texels_per_quad << " texels per quad, "
            << static_cast<int>(100 * atlas.texture_use + 0.5) << " % of the texture used\n";
}

// --atlas-out: the quad mesh with its texture atlas (atlas/quad_atlas.h), and the report's "atlas"
// object; false (with a message) when the atlas cannot be made or written.
bool write_atlas_output(const CommandLine& cl, const qgp::Session& session, qgp::Json& report) {
  if (cl.atlas_out.empty()) return true;
  try {
    qgp::AtlasOptions options = cl.atlas;
    options.texture_width = options.texture_height = cl.texture_size;
    const qgp::QuadAtlas atlas = qgp::build_quad_atlas(*session.quad_result(), options);
    report["atlas"] = atlas;
    std::ostringstream header;
    header << "qgp quad mesh of " << cl.input << " with a texture atlas: " << atlas.texture_width << " x "
           << atlas.texture_height << " texels, " << atlas.texels_per_quad << " per quad side, " << atlas.num_charts
           << " charts";
    qgp::cli::write_quad_obj(cl.atlas_out, *session.quad_result(), nullptr, {}, header.str(), &atlas.corner_uv);
    print_atlas_summary("atlas", atlas);
    return true;
  } catch (const std::exception& e) {
    std::cerr << "qgp: " << e.what() << "\n";
    return false;
  }
}

// --uv-atlas-out: the integer-grid map's triangles with a texture atlas of them (atlas/polygon_atlas.h), and the
// report's "uv_atlas" object; false (with a message) when there is no integer-grid map or no atlas.
bool write_uv_atlas_output(const CommandLine& cl, const qgp::Session& session, qgp::Json& report) {
  if (cl.uv_atlas_out.empty()) return true;
  try {
    qgp::UvMapKind kind = qgp::UvMapKind::Seamless;
    if (!qgp::available_uv_map(session, &kind) || kind != qgp::UvMapKind::IntegerGrid)
      throw qgp::Error(qgp::ErrorCode::StageFailed,
                       "no integer-grid map for every part; '" + cl.uv_atlas_out + "' not written");
    const qgp::UvMesh map = qgp::compose_uv_mesh(session, kind);
    qgp::PolygonSoup triangles;
    for (int f = 0; f < map.mesh.num_faces(); ++f) triangles.add_face(map.mesh.F.row(f).data(), 3);
    std::vector<qgp::CornerUv> grid_uv(map.uv.rows());
    for (size_t c = 0; c < grid_uv.size(); ++c) grid_uv[c] = {map.uv(c, 0), map.uv(c, 1)};
    qgp::AtlasOptions options = cl.atlas;
    options.texture_width = options.texture_height = cl.texture_size;
    const qgp::PolygonAtlas atlas = qgp::build_polygon_atlas(triangles, grid_uv, options);
    report["uv_atlas"] = atlas;
    qgp::cli::UvMatrix uv(atlas.corner_uv.size(), 2);
    for (size_t c = 0; c < atlas.corner_uv.size(); ++c) uv.row(c) << atlas.corner_uv[c][0], atlas.corner_uv[c][1];
    std::ostringstream header;
    header << "qgp integer-grid map of " << cl.input << " with a texture atlas: " << atlas.texture_width << " x "
           << atlas.texture_height << " texels, " << atlas.texels_per_quad << " per grid unit, " << atlas.num_charts
           << " charts";
    qgp::cli::write_obj(cl.uv_atlas_out, map.mesh, &uv, header.str());
    print_atlas_summary("uv atlas", atlas);
    return true;
  } catch (const std::exception& e) {
    std::cerr << "qgp: " << e.what() << "\n";
    return false;
  }
}

// Writes whatever the session has for the optional outputs; false if a requested one could not be
// written (with a message). After a failed run (run_failed) an output the run did not get to is
// named but is not a write failure: the run's own error decides the exit code.
bool write_optional_outputs(const CommandLine& cl, const qgp::Session* session, bool run_failed) {
  bool ok = true;
  auto attempt = [&](const std::string& path, const char* what, bool available, auto write) {
    if (path.empty()) return;
    if (!available) {
      std::cerr << "qgp: no " << what << " was computed; '" << path << "' not written\n";
      ok = ok && run_failed;
      return;
    }
    try {
      write();
    } catch (const std::exception& e) {
      std::cerr << "qgp: " << e.what() << "\n";
      ok = false;
    }
  };
  qgp::UvMapKind map = qgp::UvMapKind::Seamless;
  const bool has_map = session && qgp::available_uv_map(*session, &map);
  attempt(cl.uv_out, "parametrization", has_map, [&] { write_uv_output(cl.uv_out, *session, map); });
  attempt(cl.layout_out, "T-mesh layout", session && qgp::has_layout(*session),
          [&] { write_layout_output(cl.layout_out, *session); });
  return ok;
}

void print_remesh_summary(const qgp::Json& report) {
  if (!report.contains("quad")) return;
  const qgp::Json& q = report["quad"];
  std::cout << "quads " << q.value("faces", 0) << ", vertices " << q.value("vertices", 0) << ", irregular vertices "
            << q.value("irregular_vertices", 0) << ", min scaled Jacobian " << q.value("min_scaled_jacobian", 0.0)
            << ", " << report["timings_s"].value("total", 0.0) << " s, peak memory "
            << static_cast<long>(report.value("peak_memory_mb", 0.0)) << " MB\n";
  const qgp::Json count = report.contains("quantization") ? report["quantization"].value("count", qgp::Json::object())
                                                          : qgp::Json::object();
  if (count.contains("note")) std::cout << "note: " << count["note"].get<std::string>() << "\n";
  const int flipped = q.value("flipped_quads", 0);
  if (flipped > 0)
    std::cout << "warning: " << flipped << " quad(s) face against the input surface (report: quad.flipped_quad_ids, "
              << "0-based face order of the output); the surface folds within them\n";
  const int collapsed = q.value("collapsed_edge_quads", 0);
  if (collapsed > 0)
    std::cout << "warning: " << collapsed << " quad(s) have an edge of almost no length, two corners on one point "
              << "(report: quad.collapsed_edge_quad_ids)\n";
}

// How a rescued component was quadded, for its warning.
std::string rescue_phrase(const qgp::Json& rescued) {
  if (rescued["rescue"] == "split triangles") return "by splitting its triangles";
  if (rescued["rescue"] == "isotropic working mesh") return "on an isotropic remesh of its triangles";
  if (rescued["rescue"] == "finer density")
    return "at " + rescued["edge_length_factor"].dump() + " of the quad edge length";
  return "again with the cross field that keeps its close singularity pairs";
}

// Names the components whose layout gave no quads and how they were quadded (stderr).
void print_rescued_components(const qgp::Json& report) {
  for (const auto& s : report.value("rescued_components", qgp::Json::array()))
    std::cerr << "qgp: warning: component " << s["component"] << " (" << s["triangles"] << " triangles) quadded "
              << rescue_phrase(s) << " into " << s["quads"]
              << " quads, as its own gave none valid: " << s["stage"].get<std::string>() << ": "
              << s["message"].get<std::string>() << "\n";
}

// Names the components kept as triangles (stderr); true if there are any.
bool print_failed_components(const qgp::Json& report) {
  const qgp::Json failed = report.value("failed_components", qgp::Json::array());
  for (const auto& f : failed)
    std::cerr << "qgp: component " << f["component"] << " (" << f["triangles"]
              << " triangles) kept as triangles: " << f["stage"].get<std::string>() << ": "
              << f["message"].get<std::string>() << "\n";
  if (!failed.empty()) std::cerr << "qgp: complete except " << failed.size() << " component(s) written as triangles\n";
  return !failed.empty();
}

int run(const CommandLine& cl) {
  qgp::Json report;
  std::unique_ptr<qgp::Session> session;
  try {
    session = std::make_unique<qgp::Session>(qgp::read_mesh_file(cl.input));
    qgp::RemeshOptions options = cl.options;
    options.fallback_uv_map = !cl.uv_out.empty() || !cl.uv_atlas_out.empty();
    if (!cl.features.empty()) options.feature_edges = read_feature_pairs(cl.features);
    if (!cl.density.empty()) options.density = read_density(cl.density);
    session->set_options(options);
    qgp::Progress progress;
    {
      PipelineRunning running;
      session->run(cl.command == "info" ? qgp::Job::Intake : qgp::Job::Remesh, progress);
    }
    report = session->report();
  } catch (const qgp::Error& e) {
    report = session ? session->report() : qgp::Json::object();
    report["status"] = "error";
    report["error"] = {{"code", qgp::error_code_name(e.code())}, {"message", e.what()}};
    report["file"] = cl.input;
    if (cl.command == "info") print_intake_summary(report);
    // Earlier stages' results (seamless map, T-mesh) are still written for inspection.
    write_optional_outputs(cl, session.get(), true);
    write_report(cl.report, report);
    std::cerr << "qgp: " << e.what() << "\n";
    return exit_code_for(e.code());
  }
  report["file"] = cl.input;
  bool written = true;
  if (cl.command == "info") {
    print_intake_summary(report);
  } else {
    try {
      std::ostringstream header;
      header << "qgp quad mesh of " << cl.input;
      qgp::cli::write_quad_obj(cl.output, *session->quad_result(), session->kept_triangles(), session->kept_component(),
                               header.str());
    } catch (const std::exception& e) {
      std::cerr << "qgp: " << e.what() << "\n";
      written = false;
    }
    written = write_atlas_output(cl, *session, report) && written;
    written = write_uv_atlas_output(cl, *session, report) && written;
    print_remesh_summary(report);
    print_rescued_components(report);
  }
  written = write_optional_outputs(cl, session.get(), false) && written;
  written = write_report(cl.report, report) && written;
  if (!written) return 1;
  return print_failed_components(report) ? 5 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  report_abnormal_ends();
  CommandLine cl;
  int exit_code = 0;
  if (!parse(argc, argv, &cl, &exit_code)) return exit_code;
  try {
    return cl.command == "stitch" ? qgp::cli::run_stitch(cl.stitch) : run(cl);
  } catch (const std::exception& e) {
    std::cerr << "qgp: internal error: " << e.what() << "\n";
    return 4;
  }
}
