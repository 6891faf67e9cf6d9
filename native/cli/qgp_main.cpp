// qgp: command-line front end of the native pipeline, for batch use and tests.
//
// Exit codes: 0 success, 1 bad command line, 2 unusable input (with a one-line reason on
// stderr), 3 a pipeline stage failed or is not built yet, 4 internal error (also when the process
// is ended from inside a library, e.g. MUMPS calling exit, or by a fatal signal: see
// report_abnormal_ends).
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

#include "core/error.h"
#include "core/json.h"
#include "intake/read_mesh_file.h"
#include "mesh_writers.h"
#include "pipeline/session.h"
#include "pipeline/uv_mesh.h"
#include "tmesh/tmesh_system.h"

namespace {

const char* kUsage =
    "usage:\n"
    "  qgp info IN [--report R.json] [--drop-bad-components]\n"
    "  qgp remesh IN -o OUT.obj [--faces N | --edge-length L] [--sharp-angle DEG]\n"
    "             [--features FILE] [--uv-out UV.obj] [--layout-out LAYOUT.obj]\n"
    "             [--report R.json] [--quantizer greedy|round] [--drop-bad-components]\n"
    "IN: .obj, .ply or .off. --features FILE: one vertex-index pair per line (0-based).\n";

// --- Abnormal ends: a library under the pipeline (MUMPS: "** MPI_ABORT called", then a Fortran
// STOP, i.e. exit(0)) or a fatal signal must never look like success to a batch script.
std::atomic<bool> g_pipeline_running{false};

void write_stderr(const char* text) {
  ssize_t ignored = write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

void exit_during_pipeline() {
  if (!g_pipeline_running.load()) return;
  write_stderr("qgp: internal error: a library under the pipeline ended the process (its message, if any, is "
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
                     : sig == SIGBUS  ? "crashed (SIGBUS)"
                                      : "crashed (SIGFPE)";
  write_stderr("qgp: internal error: ");
  write_stderr(what);
  write_stderr("; no output was written\n");
  signal(sig, SIG_DFL);
  raise(sig);
}

void report_abnormal_ends() {
  std::atexit(exit_during_pipeline);
  struct sigaction action {};
  action.sa_handler = fatal_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (int sig : {SIGSEGV, SIGABRT, SIGBUS, SIGFPE}) sigaction(sig, &action, nullptr);
}

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CommandLine {
  std::string command, input, output, report, features, uv_out, layout_out;
  qgp::RemeshOptions options;
};

double parse_number(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') throw UsageError(flag + " expects a number, got '" + text + "'");
  return v;
}

CommandLine parse(int argc, char** argv) {
  if (argc < 3) throw UsageError("missing command or input file");
  CommandLine cl;
  cl.command = argv[1];
  if (cl.command != "info" && cl.command != "remesh") throw UsageError("unknown command '" + cl.command + "'");
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--report") cl.report = value();
    else if (arg == "--drop-bad-components") cl.options.drop_bad_components = true;
    else if (cl.command == "remesh" && (arg == "-o" || arg == "--output")) cl.output = value();
    else if (cl.command == "remesh" && arg == "--faces") cl.options.target_faces = parse_number(arg, value());
    else if (cl.command == "remesh" && arg == "--edge-length") cl.options.edge_length = parse_number(arg, value());
    else if (cl.command == "remesh" && arg == "--sharp-angle") cl.options.sharp_angle_deg = parse_number(arg, value());
    else if (cl.command == "remesh" && arg == "--features") cl.features = value();
    else if (cl.command == "remesh" && arg == "--uv-out") cl.uv_out = value();
    else if (cl.command == "remesh" && arg == "--layout-out") cl.layout_out = value();
    else if (cl.command == "remesh" && arg == "--quantizer") {
      const std::string q = value();
      if (q != "greedy" && q != "round") throw UsageError("--quantizer must be greedy or round");
      cl.options.quantizer = qgp::parse_quantizer(q);
    } else if (!arg.empty() && arg[0] == '-') throw UsageError("unknown option '" + arg + "'");
    else if (cl.input.empty()) cl.input = arg;
    else throw UsageError("unexpected argument '" + arg + "'");
  }
  if (cl.input.empty()) throw UsageError("missing input file");
  if (cl.command == "remesh" && cl.output.empty()) throw UsageError("remesh needs -o OUT.obj");
  if (cl.options.target_faces > 0 && cl.options.edge_length > 0)
    throw UsageError("give --faces or --edge-length, not both");
  if (cl.options.target_faces < 0 || cl.options.edge_length < 0)
    throw UsageError("--faces and --edge-length must be positive");
  return cl;
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
      throw qgp::Error(qgp::ErrorCode::InvalidArgument, "features file '" + path + "' line " +
                                                            std::to_string(line_no) +
                                                            ": expected two vertex indices");
    pairs.push_back({static_cast<int>(a), static_cast<int>(b)});
  }
  return pairs;
}

void write_report(const std::string& path, const qgp::Json& report) {
  if (path.empty()) return;
  std::ofstream out(path);
  if (!out) {
    std::cerr << "qgp: cannot write report '" << path << "'\n";
    return;
  }
  out << report.dump(2) << "\n";
}

void print_intake_summary(const qgp::Json& report) {
  if (!report.contains("input")) return;
  const qgp::Json& in = report["input"];
  std::cout << "vertices " << in["vertices"] << ", faces " << in["faces"] << " (input "
            << in["input_vertices"] << " / " << in["input_faces"] << ")\n";
  std::cout << "components " << in["components"] << ", genus " << in["genus"].dump()
            << ", boundary loops " << in["boundary_loops"].dump() << "\n";
  for (const auto& r : in["repairs"]) std::cout << "repair " << r["kind"].get<std::string>() << ": " << r["count"] << "\n";
  for (const auto& w : in["warnings"]) std::cout << "warning: " << w.get<std::string>() << "\n";
}

int exit_code_for(qgp::ErrorCode code) {
  switch (code) {
    case qgp::ErrorCode::InvalidMesh:
    case qgp::ErrorCode::UnreadableFile: return 2;
    case qgp::ErrorCode::InvalidArgument: return 1;
    case qgp::ErrorCode::NotBuilt:
    case qgp::ErrorCode::StageFailed:
    case qgp::ErrorCode::Cancelled: return 3;
    default: return 4;
  }
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
           << session.components()[0].seamless_edge_length() << " model units";
  qgp::cli::write_obj(path, out.mesh, &out.uv, header.str());
}

// --layout-out: the T-mesh (motorcycle graph) of every component as OBJ polylines.
bool has_layout(const qgp::Session& session) {
  bool complete = !session.components().empty();
  for (const auto& c : session.components())
    complete = complete && c.seamless_is_current() && c.traced.computed_from(c.seamless.id());
  return complete;
}

void write_layout_output(const std::string& path, const qgp::Session& session) {
  std::vector<const qgp::TriMesh*> meshes;
  std::vector<const qgp::TMesh*> tmeshes;
  for (const auto& c : session.components()) {
    meshes.push_back(&c.mesh);
    tmeshes.push_back(&c.traced->tmesh);
  }
  qgp::write_layout_obj(path, meshes, tmeshes);
}

// Writes whatever the session has for the optional outputs; false if a requested one could not be
// written (with a message).
bool write_optional_outputs(const CommandLine& cl, const qgp::Session* session) {
  bool ok = true;
  auto attempt = [&](const std::string& path, const char* what, bool available, auto write) {
    if (path.empty()) return;
    if (!available) {
      std::cerr << "qgp: no " << what << " was computed; '" << path << "' not written\n";
      ok = false;
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
  attempt(cl.layout_out, "T-mesh layout", session && has_layout(*session),
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
  const int flipped = q.value("flipped_quads", 0);
  if (flipped > 0)
    std::cout << "warning: " << flipped << " quad(s) face against the input surface (report: quad.flipped_quad_ids, "
              << "0-based face order of the output); the surface folds within them\n";
}

int run(const CommandLine& cl) {
  qgp::Json report;
  std::unique_ptr<qgp::Session> session;
  try {
    session = std::make_unique<qgp::Session>(qgp::read_mesh_file(cl.input));
    qgp::RemeshOptions options = cl.options;
    options.fallback_uv_map = !cl.uv_out.empty();
    if (!cl.features.empty()) options.feature_edges = read_feature_pairs(cl.features);
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
    const bool written = write_optional_outputs(cl, session.get());
    write_report(cl.report, report);
    std::cerr << "qgp: " << e.what() << "\n";
    return written ? exit_code_for(e.code()) : 1;
  }
  report["file"] = cl.input;
  bool written = true;
  if (cl.command == "info") {
    print_intake_summary(report);
  } else {
    try {
      std::ostringstream header;
      header << "qgp quad mesh of " << cl.input;
      qgp::cli::write_quad_obj(cl.output, *session->quad_result(), header.str());
    } catch (const std::exception& e) {
      std::cerr << "qgp: " << e.what() << "\n";
      written = false;
    }
    print_remesh_summary(report);
  }
  written = write_optional_outputs(cl, session.get()) && written;
  write_report(cl.report, report);
  return written ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  report_abnormal_ends();
  CommandLine cl;
  try {
    cl = parse(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "qgp: " << e.what() << "\n" << kUsage;
    return 1;
  }
  try {
    return run(cl);
  } catch (const std::exception& e) {
    std::cerr << "qgp: internal error: " << e.what() << "\n";
    return 4;
  }
}
