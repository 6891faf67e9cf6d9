#include "seamless_map/parametrization_problem.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/blas_kernels.h"
#include "core/error.h"
#include "core/timer.h"
#include "seamless_map/linear_elimination.h"
#include "seamless_map/orientation.h"
#include "seamless_map/quadratic_program.h"

namespace qgp {

namespace {

using SpMat = Eigen::SparseMatrix<double>;
using Triplet = Eigen::Triplet<double>;

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// (R^r p)[axis] = sign * p[source axis]
struct RotatedAxis {
  int axis;
  double sign;
};
RotatedAxis rotated_axis(int r, int axis) {
  switch (((r % 4) + 4) % 4) {
    case 0: return {axis, 1};
    case 1: return axis == 0 ? RotatedAxis{1, -1} : RotatedAxis{0, 1};
    case 2: return {axis, -1};
    default: return axis == 0 ? RotatedAxis{1, 1} : RotatedAxis{0, -1};
  }
}

// kWound: positive, but around a vertex whose one-ring winds a full turn off its cone angle.
enum FaceState : char { kHealthy = 0, kThin = 1, kDegenerate = 2, kFlipped = 3, kForced = 4, kWound = 5 };
// Reference triangles of bad faces: kUnfold: the current triangle with one vertex moved across its
// opposite edge (the smallest change; keeps isoline edges); kPropagated: the ideal shape rotated
// like the healthy neighbourhood; kOwnFit: the ideal shape rotated to fit the current one;
// kAllElastic: as kPropagated, and healthy faces may leave their sectors too (at a cost).
enum RepairStrategy { kUnfold = 0, kPropagated = 1, kOwnFit = 2, kAllElastic = 3 };

}  // namespace

// Elimination and energy for one constraint mode.
struct ParametrizationProblem::System {
  // Eliminates the hard constraints of `problem` and assembles its energy in the free variables
  // (plus, in Penalty mode, the caller's linear constraints weighted by penalty_weight).
  System(const ParametrizationProblem& problem, ConstraintMode constraint_mode, double weight, Progress& progress);

  const std::vector<int>& wedge_of;  // the problem's corner -> wedge
  ConstraintMode mode = ConstraintMode::Hard;
  double penalty_weight = 0;
  int num_free = 0;
  int non_integer_pivots = 0, redundant = 0, inconsistent = 0;
  // Coordinate (wedge w, axis a) = sum form_coeff * z[form_var] + form_const, row 2w + a.
  std::vector<int> form_start;
  std::vector<int> form_var;
  std::vector<double> form_coeff;
  std::vector<double> form_const;
  SpMat Q;  // objective z^T Q z - 2 c^T z + d2 (energy + penalty)
  Eigen::VectorXd c;
  double d2 = 0;
  Eigen::CholmodDecomposition<SpMat, Eigen::Lower> cholesky;
  bool factorized = false;
  std::vector<int> var_face_start, var_face;  // free variable -> faces whose corners use it
  std::vector<char> shared_var;               // free variables in the coordinates of more than one vertex (see
                                              // Solver::start_moving_shared_coordinates)
  std::vector<char> forced_degenerate;        // #F

 private:
  // Variable (before the elimination) of coordinate `axis` of the wedge of `corner`.
  int wedge_var(int corner, int axis) const { return 2 * wedge_of[corner] + axis; }
  // The exact elimination of the hard constraints: pin, transitions, isolines and, in Hard mode,
  // the caller's linear constraints.
  LinearElimination eliminate(const ParametrizationProblem& problem) const;
  // Every wedge coordinate as a form in the free variables (form_*), and the elimination's counts.
  void expand_forms(LinearElimination& elim, int num_wedges);
  // True when coordinates va and vb have the same form (are equal by the hard constraints alone).
  bool same_form(int va, int vb) const;
  // Marks the faces whose three corners share a coordinate (or two corners coincide) by the hard
  // constraints alone.
  void find_forced_degenerate(const ParametrizationProblem& problem);
  // Q, c and d2 from the least-squares rows of the energy (and of the penalty when with_penalty).
  void assemble_energy(const ParametrizationProblem& problem, bool with_penalty, Progress& progress);
  // Appends the energy's least-squares rows (per face and axis the two gradient components,
  // weighted by sqrt(area)); returns their number.
  int add_energy_rows(const ParametrizationProblem& problem, std::vector<Triplet>& triplets, std::vector<double>& rhs,
                      Progress& progress) const;
  // Appends one penalty row per linear constraint from row `row` on; returns the next row.
  int add_penalty_rows(const ParametrizationProblem& problem, int row, std::vector<Triplet>& triplets,
                       std::vector<double>& rhs) const;
  // Fills var_face_start / var_face (free variable -> faces) and shared_var.
  void index_variable_faces(const ParametrizationProblem& problem);
};

ParametrizationProblem::ParametrizationProblem(const TriMesh& mesh, std::vector<int8_t> rotation,
                                               std::vector<char> is_cut, std::vector<Vec3> frame_u, double edge_length,
                                               const std::vector<double>& face_size)
    : mesh_(mesh), rotation_(std::move(rotation)), is_cut_(std::move(is_cut)) {
  const int nf = mesh.num_faces(), nc = 3 * nf;
  if (nf == 0 || static_cast<int>(mesh.opposite.size()) != nc)
    throw Error(ErrorCode::InvalidArgument, "parametrization: the mesh has no faces or no connectivity");
  if (static_cast<int>(rotation_.size()) != nc || static_cast<int>(frame_u.size()) != nf ||
      (!is_cut_.empty() && static_cast<int>(is_cut_.size()) != mesh.num_edges()))
    throw Error(ErrorCode::InvalidArgument, "parametrization: rotation / cut / frame arrays do not match the mesh");
  if (!(edge_length > 0) || !std::isfinite(edge_length))
    throw Error(ErrorCode::InvalidArgument, "parametrization: the target edge length must be positive");
  if (!face_size.empty() && static_cast<int>(face_size.size()) != nf)
    throw Error(ErrorCode::InvalidArgument, "parametrization: the face sizes do not match the mesh");
  for (double s : face_size)
    if (!(s > 0) || !std::isfinite(s))
      throw Error(ErrorCode::InvalidArgument, "parametrization: a face size is not a positive number");
  if (is_cut_.empty()) is_cut_.assign(mesh.num_edges(), 0);
  for (int h = 0; h < nc; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0) {
      if (rotation_[h] % 4 != 0)
        throw Error(ErrorCode::InvalidArgument, "parametrization: rotation on a boundary edge");
      is_cut_[mesh.edge_of[h]] = 0;
      continue;
    }
    if (((rotation_[h] + rotation_[o]) % 4 + 4) % 4 != 0)
      throw Error(ErrorCode::InvalidArgument, "parametrization: rotations of opposite halfedges are not inverse");
    if (rotation_[h] % 4 != 0) is_cut_[mesh.edge_of[h]] = 1;
  }

  // Wedges: corners joined across non-cut interior edges.
  std::vector<int> parent(nc);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int h = 0; h < nc; ++h) {
    const int o = mesh.opposite[h];
    if (o < 0 || o < h) continue;
    if (is_cut_[mesh.edge_of[h]]) {
      cut_halfedges_.push_back(h);
      continue;
    }
    parent[find(h)] = find(3 * (o / 3) + (o % 3 + 1) % 3);
    parent[find(TriMesh::next(h))] = find(o);
  }
  wedge_of_.assign(nc, -1);
  std::vector<int> root_wedge(nc, -1);
  for (int c = 0; c < nc; ++c) {
    const int r = find(c);
    if (root_wedge[r] < 0) root_wedge[r] = num_wedges_++;
    wedge_of_[c] = root_wedge[r];
  }

  // Ideal shapes in each face's frame (uv units) and the gradient operators.
  ideal_.resize(nc);
  ideal_area_.resize(nf);
  gradient_.resize(nf);
  for (int f = 0; f < nf; ++f) {
    const double length = face_size.empty() ? edge_length : edge_length * face_size[f];
    const Vec3 p0 = mesh.position(mesh.F(f, 0)), p1 = mesh.position(mesh.F(f, 1)), p2 = mesh.position(mesh.F(f, 2));
    const Vec3 n = (p1 - p0).cross(p2 - p0);
    Vec2 q[3] = {Vec2::Zero(), Vec2::Zero(), Vec2::Zero()};
    bool ok = false;
    if (n.norm() > 0 && std::isfinite(n.norm())) {
      const Vec3 nn = n.normalized();
      Vec3 fu = frame_u[f] - frame_u[f].dot(nn) * nn;
      if (fu.norm() > 0 && std::isfinite(fu.norm())) {
        fu.normalize();
        const Vec3 fv = nn.cross(fu);
        q[1] = Vec2((p1 - p0).dot(fu), (p1 - p0).dot(fv)) / length;
        q[2] = Vec2((p2 - p0).dot(fu), (p2 - p0).dot(fv)) / length;
        ok = cross2(q[1], q[2]) > 0;
      }
    }
    if (!ok) {
      // Degenerate face or frame: an equilateral stand-in of the same mean edge length.
      const double len = ((p1 - p0).norm() + (p2 - p1).norm() + (p0 - p2).norm()) / 3 / length;
      if (!(len > 0) || !std::isfinite(len))
        throw Error(ErrorCode::InvalidMesh, "parametrization: face " + std::to_string(f) + " has no extent");
      q[1] = Vec2(len, 0);
      q[2] = Vec2(0.5 * len, 0.5 * std::sqrt(3.0) * len);
    }
    const double area2 = cross2(q[1] - q[0], q[2] - q[0]);
    for (int k = 0; k < 3; ++k) {
      ideal_[3 * f + k] = q[k];
      // grad phi_k = perp(q_{k+2} - q_{k+1}) / (2 A), perp(x, y) = (-y, x).
      const Vec2 d = q[(k + 2) % 3] - q[(k + 1) % 3];
      gradient_[f][k] = -d.y() / area2;
      gradient_[f][3 + k] = d.x() / area2;
    }
    ideal_area_[f] = 0.5 * area2;
  }
}

ParametrizationProblem::~ParametrizationProblem() = default;

void ParametrizationProblem::add_isoline(int halfedge, int axis) {
  if (halfedge < 0 || halfedge >= mesh_.num_halfedges() || (axis != 0 && axis != 1))
    throw Error(ErrorCode::InvalidArgument, "parametrization: bad isoline");
  isolines_.push_back({halfedge, axis});
  system_.reset();
}

void ParametrizationProblem::add_linear_constraint(std::vector<CornerTerm> terms, double rhs) {
  for (const CornerTerm& t : terms)
    if (t.corner < 0 || t.corner >= mesh_.num_halfedges() || (t.axis != 0 && t.axis != 1) || !std::isfinite(t.coeff))
      throw Error(ErrorCode::InvalidArgument, "parametrization: bad linear constraint term");
  if (!std::isfinite(rhs)) throw Error(ErrorCode::InvalidArgument, "parametrization: non-finite constraint value");
  constraints_.push_back({std::move(terms), rhs});
  system_.reset();
}

void ParametrizationProblem::clear_linear_constraints() {
  constraints_.clear();
  system_.reset();
}

void ParametrizationProblem::set_cone_angles(std::vector<int> quarter_turns) {
  if (!quarter_turns.empty() && static_cast<int>(quarter_turns.size()) != mesh_.num_vertices())
    throw Error(ErrorCode::InvalidArgument, "parametrization: one cone angle per vertex expected");
  cone_quarter_turns_ = std::move(quarter_turns);
}

std::vector<int> ParametrizationProblem::winding_charges(const std::function<Vec2(int)>& corner) const {
  if (cone_quarter_turns_.empty()) return {};
  std::vector<double> angle(mesh_.num_vertices(), 0.0);
  for (int c = 0; c < 3 * mesh_.num_faces(); ++c) {
    const int f = c / 3;
    const Vec2 p = corner(c);
    const Vec2 a = corner(3 * f + (c + 1) % 3) - p, b = corner(3 * f + (c + 2) % 3) - p;
    angle[mesh_.F(f, c % 3)] += std::atan2(cross2(a, b), a.dot(b));
  }
  std::vector<int> charge(mesh_.num_vertices(), 0);
  for (int v = 0; v < mesh_.num_vertices(); ++v) {
    const double off = angle[v] - cone_quarter_turns_[v] * M_PI / 2;
    if (std::abs(off) > 1.5 * M_PI)
      charge[v] = static_cast<int>(std::lround(off / (2 * M_PI)));  // a full turn off (with slack)
  }
  return charge;
}

int ParametrizationProblem::winding_defects(const Parametrization& param) const {
  return static_cast<int>(wound_vertices(param).size());
}

std::vector<int> ParametrizationProblem::wound_vertices(const Parametrization& param) const {
  const std::vector<int> charge = winding_charges([&](int c) { return param.corner(c / 3, c % 3); });
  std::vector<int> wound;
  for (int v = 0; v < static_cast<int>(charge.size()); ++v)
    if (charge[v] != 0) wound.push_back(v);
  return wound;
}

void ParametrizationProblem::set_pin_translation(bool pin) {
  if (pin != pin_) system_.reset();
  pin_ = pin;
}

ParametrizationProblem::System& ParametrizationProblem::system(ConstraintMode mode, double penalty_weight,
                                                               Progress& progress) {
  const bool with_penalty = mode == ConstraintMode::Penalty && !constraints_.empty();
  if (system_ && system_->mode == mode && (!with_penalty || system_->penalty_weight == penalty_weight)) return *system_;
  system_.reset();
  system_ = std::make_unique<System>(*this, mode, penalty_weight, progress);
  return *system_;
}

ParametrizationProblem::System::System(const ParametrizationProblem& problem, ConstraintMode constraint_mode,
                                       double weight, Progress& progress)
    : wedge_of(problem.wedge_of_), mode(constraint_mode), penalty_weight(weight) {
  const bool with_penalty = mode == ConstraintMode::Penalty && !problem.constraints_.empty();
  LinearElimination elim = eliminate(problem);
  progress.check_cancel();
  expand_forms(elim, problem.num_wedges_);
  progress.check_cancel();
  find_forced_degenerate(problem);
  assemble_energy(problem, with_penalty, progress);
  progress.check_cancel();
  index_variable_faces(problem);
}

LinearElimination ParametrizationProblem::System::eliminate(const ParametrizationProblem& problem) const {
  const int nw = problem.num_wedges_;
  const int num_vars = 2 * nw + 2 * static_cast<int>(problem.cut_halfedges_.size());

  // Translations are preferred as pivots, then wedges: an arc's translation becomes the difference
  // of wedges at its end, and the second side of the arc R * first side + that difference. (With
  // wedges first, the cone positions became functions of the translations and every wedge a sum
  // of translations along the cut tree: forms of thousands of terms on meshes with many
  // singularities, a dense energy matrix and slow repair solves.)
  LinearElimination elim(num_vars);
  for (int v = 0; v < 2 * nw; ++v) elim.set_priority(v, 1);
  for (int v = 2 * nw; v < num_vars; ++v) elim.set_priority(v, 2);
  if (problem.pin_) {
    for (int a = 0; a < 2; ++a) {
      elim.set_priority(wedge_var(0, a), 3);
      elim.add_equation({{wedge_var(0, a), 1.0}}, 0.0);
    }
  }
  for (size_t k = 0; k < problem.cut_halfedges_.size(); ++k) {
    const int h = problem.cut_halfedges_[k], o = problem.mesh_.opposite[h];
    const int ends[2][2] = {{h, TriMesh::next(o)}, {TriMesh::next(h), o}};  // (corner in f, corner in g)
    for (const auto& end : ends)
      for (int a = 0; a < 2; ++a) {
        const RotatedAxis ra = rotated_axis(problem.rotation_[h], a);
        elim.add_equation({{wedge_var(end[1], a), 1.0},
                           {wedge_var(end[0], ra.axis), -ra.sign},
                           {2 * nw + 2 * static_cast<int>(k) + a, -1.0}},
                          0.0);
      }
  }
  for (const auto& [h, axis] : problem.isolines_)
    elim.add_equation({{wedge_var(h, axis), 1.0}, {wedge_var(TriMesh::next(h), axis), -1.0}}, 0.0);
  if (mode == ConstraintMode::Hard)
    for (const LinearConstraint& lc : problem.constraints_) {
      LinearForm form;
      for (const CornerTerm& t : lc.terms) form.push_back({wedge_var(t.corner, t.axis), t.coeff});
      elim.add_equation(std::move(form), lc.rhs);
    }
  return elim;
}

void ParametrizationProblem::System::expand_forms(LinearElimination& elim, int num_wedges) {
  const int nw = num_wedges;
  non_integer_pivots = elim.non_integer_pivots();
  redundant = elim.redundant_equations();
  inconsistent = elim.inconsistent_equations();
  const std::vector<int> free_index = elim.free_index();
  num_free = static_cast<int>(elim.free_variables().size());
  form_start.assign(2 * nw + 1, 0);
  form_const.assign(2 * nw, 0.0);
  for (int v = 0; v < 2 * nw; ++v) {
    double constant = 0;
    const LinearForm form = elim.expansion(v, &constant);
    for (const LinearTerm& t : form) {
      form_var.push_back(free_index[t.var]);
      form_coeff.push_back(t.coeff);
    }
    form_const[v] = constant;
    form_start[v + 1] = static_cast<int>(form_var.size());
  }
}

bool ParametrizationProblem::System::same_form(int va, int vb) const {
  if (form_const[va] != form_const[vb]) return false;
  const int la = form_start[va + 1] - form_start[va], lb = form_start[vb + 1] - form_start[vb];
  if (la != lb) return false;
  for (int i = 0; i < la; ++i)
    if (form_var[form_start[va] + i] != form_var[form_start[vb] + i] ||
        form_coeff[form_start[va] + i] != form_coeff[form_start[vb] + i])
      return false;
  return true;
}

void ParametrizationProblem::System::find_forced_degenerate(const ParametrizationProblem& problem) {
  const int nf = problem.mesh_.num_faces();
  forced_degenerate.assign(nf, 0);
  for (int f = 0; f < nf; ++f) {
    for (int a = 0; a < 2; ++a)
      if (same_form(wedge_var(3 * f, a), wedge_var(3 * f + 1, a)) &&
          same_form(wedge_var(3 * f, a), wedge_var(3 * f + 2, a)))
        forced_degenerate[f] = 1;
    for (int k = 0; k < 3; ++k) {
      const int c0 = 3 * f + k, c1 = 3 * f + (k + 1) % 3;
      if (same_form(wedge_var(c0, 0), wedge_var(c1, 0)) && same_form(wedge_var(c0, 1), wedge_var(c1, 1)))
        forced_degenerate[f] = 1;
    }
  }
}

void ParametrizationProblem::System::assemble_energy(const ParametrizationProblem& problem, bool with_penalty,
                                                     Progress& progress) {
  const int nf = problem.mesh_.num_faces();
  std::vector<Triplet> triplets;
  std::vector<double> rhs;
  triplets.reserve(static_cast<size_t>(nf) * 16);
  rhs.reserve(static_cast<size_t>(4) * nf);
  int row = add_energy_rows(problem, triplets, rhs, progress);
  if (with_penalty) row = add_penalty_rows(problem, row, triplets, rhs);
  SpMat M(row, num_free);
  M.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};
  const Eigen::Map<const Eigen::VectorXd> d(rhs.data(), row);
  Q = SpMat(M.transpose() * M);
  c = M.transpose() * d;
  d2 = d.squaredNorm();
}

int ParametrizationProblem::System::add_energy_rows(const ParametrizationProblem& problem,
                                                    std::vector<Triplet>& triplets, std::vector<double>& rhs,
                                                    Progress& progress) const {
  const int nf = problem.mesh_.num_faces();
  int row = 0;
  for (int f = 0; f < nf; ++f) {
    const double w = std::sqrt(problem.ideal_area_[f]);
    for (int a = 0; a < 2; ++a)
      for (int j = 0; j < 2; ++j, ++row) {
        double b = (a == j) ? w : 0.0;  // target gradient: (1,0) for u, (0,1) for v
        for (int k = 0; k < 3; ++k) {
          const double g = w * problem.gradient_[f][3 * j + k];
          const int v = wedge_var(3 * f + k, a);
          for (int i = form_start[v]; i < form_start[v + 1]; ++i)
            triplets.emplace_back(row, form_var[i], g * form_coeff[i]);
          b -= g * form_const[v];
        }
        rhs.push_back(b);
      }
    if ((f & 0xffff) == 0) progress.check_cancel();
  }
  return row;
}

int ParametrizationProblem::System::add_penalty_rows(const ParametrizationProblem& problem, int row,
                                                     std::vector<Triplet>& triplets, std::vector<double>& rhs) const {
  const double w = std::sqrt(penalty_weight);
  for (const LinearConstraint& lc : problem.constraints_) {
    double b = w * lc.rhs;
    for (const CornerTerm& t : lc.terms) {
      const int v = wedge_var(t.corner, t.axis);
      for (int i = form_start[v]; i < form_start[v + 1]; ++i)
        triplets.emplace_back(row, form_var[i], w * t.coeff * form_coeff[i]);
      b -= w * t.coeff * form_const[v];
    }
    rhs.push_back(b);
    ++row;
  }
  return row;
}

void ParametrizationProblem::System::index_variable_faces(const ParametrizationProblem& problem) {
  const int nf = problem.mesh_.num_faces();
  std::vector<std::pair<int, int>> pairs;  // (var, face)
  std::vector<int> first_vertex(num_free, -1);
  shared_var.assign(num_free, 0);
  for (int f = 0; f < nf; ++f) {
    const size_t first = pairs.size();
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 2; ++a) {
        const int v = wedge_var(3 * f + k, a);
        for (int i = form_start[v]; i < form_start[v + 1]; ++i) {
          const int var = form_var[i], vertex = problem.mesh_.F(f, k);
          pairs.push_back({var, f});
          if (first_vertex[var] < 0) first_vertex[var] = vertex;
          shared_var[var] = shared_var[var] || first_vertex[var] != vertex;
        }
      }
    std::sort(pairs.begin() + static_cast<long>(first), pairs.end());
    pairs.erase(std::unique(pairs.begin() + static_cast<long>(first), pairs.end()), pairs.end());
  }
  std::sort(pairs.begin(), pairs.end());
  var_face_start.assign(num_free + 1, 0);
  for (const auto& p : pairs) ++var_face_start[p.first + 1];
  for (int v = 0; v < num_free; ++v) var_face_start[v + 1] += var_face_start[v];
  var_face.resize(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) var_face[i] = pairs[i].second;
}

namespace {

// Evaluation helpers bound to one system.
struct Evaluator {
  const TriMesh& mesh;
  const std::vector<int>& wedge_of;
  const std::vector<int>& form_start;
  const std::vector<int>& form_var;
  const std::vector<double>& form_coeff;
  const std::vector<double>& form_const;

  int var(int corner, int axis) const { return 2 * wedge_of[corner] + axis; }
  double coordinate(const Eigen::VectorXd& z, int corner, int axis) const {
    const int v = var(corner, axis);
    double s = form_const[v];
    for (int i = form_start[v]; i < form_start[v + 1]; ++i) s += form_coeff[i] * z[form_var[i]];
    return s;
  }
  Vec2 corner(const Eigen::VectorXd& z, int c) const { return Vec2(coordinate(z, c, 0), coordinate(z, c, 1)); }
};

}  // namespace

std::vector<int> ParametrizationProblem::forced_degenerate_faces(Progress& progress) {
  const System& sys = system(ConstraintMode::Hard, 0, progress);
  std::vector<int> faces;
  for (int f = 0; f < mesh_.num_faces(); ++f)
    if (sys.forced_degenerate[f]) faces.push_back(f);
  return faces;
}

double ParametrizationProblem::field_energy(const Parametrization& param) const {
  double e = 0;
  for (int f = 0; f < mesh_.num_faces(); ++f) {
    const auto& g = gradient_[f];
    for (int a = 0; a < 2; ++a)
      for (int j = 0; j < 2; ++j) {
        double s = (a == j) ? -1.0 : 0.0;
        for (int k = 0; k < 3; ++k) s += g[3 * j + k] * param.uv(3 * f + k, a);
        e += ideal_area_[f] * s * s;
      }
  }
  return e;
}

double ParametrizationProblem::constraint_violation(const Parametrization& param) const {
  double worst = 0;
  for (const LinearConstraint& lc : constraints_) {
    double s = -lc.rhs;
    for (const CornerTerm& t : lc.terms) s += t.coeff * param.uv(t.corner, t.axis);
    worst = std::max(worst, std::abs(s));
  }
  return worst;
}

namespace {

// Faces by state in one pose (see ParametrizationProblem::Solver::census).
struct Census {
  std::vector<char> state;
  std::vector<char> wound;  // #F: in a region around wound vertices (see mark_wound)
  int flipped = 0, degenerate = 0, thin = 0, forced = 0, wound_faces = 0;
  bool field_frame = false;  // every bad face's reference is its ideal shape in the field's frame
  double min_ratio = 0;
  double depth = 0;  // sum over bad faces of (min_area_ratio - area / ideal area)
  int bad() const { return flipped + degenerate + thin + wound_faces; }
};

// Faces the repair works on: all but healthy and forced degenerate ones.
bool is_bad(char state) { return state != kHealthy && state != kForced; }

// The best pose of a local repair and the rounds since the last accepted one.
struct RepairTrack {
  Census best;  // the best pose seen (fewest bad faces, then least depth)
  Eigen::VectorXd best_z;
  int best_round = -1;
  int rejected = 0;
  int fewer_bad_round = 0;  // the last round that lowered the best pose's bad faces (0 if none did)
  int wide_rounds = 0;      // rounds since then over a region of at least half the faces
};

// Rotations (relative to the field) of the reference shapes of one region while they spread.
struct ReferenceRotations {
  std::vector<Vec2> rotation;  // #F unit vectors
  std::vector<char> assigned;  // #F
  std::vector<int> layer;      // faces assigned last, whose neighbours follow
};

// The QP of one Ipopt solve over a region's variables, as it is built.
struct RegionQP {
  std::vector<int> local;  // free variable -> QP variable, or -1 (stays fixed)
  std::vector<int> vars;   // QP variable -> free variable
  std::vector<int> faces;  // faces with tri-sector constraints
  SparseQP qp;
  std::vector<Triplet> ct;  // constraint matrix entries
  std::vector<double> lower;
  std::vector<std::pair<int, double>> elastic;  // (row, cost per unit of violation)
  int rows = 0;
};

// Bisector directions of a positively oriented triangle r: bound[k] between edge k-1 and edge k.
void sector_bisectors(const Vec2 r[3], Vec2 bound[3]) {
  Vec2 dir[3];
  for (int k = 0; k < 3; ++k) dir[k] = (r[(k + 1) % 3] - r[k]).normalized();
  for (int k = 0; k < 3; ++k) {  // bisector between edge k-1 and edge k
    const Vec2& a = dir[(k + 2) % 3];
    const double turn = std::atan2(cross2(a, dir[k]), a.dot(dir[k]));  // in (0, pi)
    const double half = 0.5 * turn;
    bound[k] = Vec2(a.x() * std::cos(half) - a.y() * std::sin(half), a.x() * std::sin(half) + a.y() * std::cos(half));
  }
}

}  // namespace

// One solve(): the equality-only optimum by sparse Cholesky, then the regularity repair with
// Ipopt under tri-sector constraints (Bommes et al. 2013) and the re-linearization around the
// regular pose (paper §7.1). Holds the pose and the repair's face sets between these phases.
class ParametrizationProblem::Solver {
 public:
  Solver(const ParametrizationProblem& problem, System& sys, const ParametrizationSolveOptions& options,
         Progress& progress, ParametrizationSolution& out);
  // Runs every phase and fills the solution.
  void run();

 private:
  // Reports fraction t of the caller's progress range.
  void report(double t) const;
  // Solution statistics of the system (free variables, elimination counts).
  void record_system_stats();
  // Equality-only optimum z = Q^-1 c by sparse Cholesky (factorized once per system).
  void solve_equality_only();
  // Vertex -> faces (vf_start_ / vf_) for region growth.
  void index_vertex_faces();
  // Energy and bad faces of the equality-only optimum.
  void record_initial_stats();
  // Faces with isoline edges: the rotation (relative to the field) that puts the ideal isoline
  // edges exactly on their axes (unit vector; zero for other faces).
  void find_isoline_rotations();
  // The final pose and its statistics.
  void write_output();

  // Objective (energy + penalty) of free variables x.
  double objective(const Eigen::VectorXd& x) const { return x.dot(sys_.Q * x) - 2 * sys_.c.dot(x) + sys_.d2; }
  // State of face f in pose x; *ratio = parametric / ideal area.
  FaceState classify_face(const Eigen::VectorXd& x, int f, double* ratio) const;
  // Every face's state in pose x, with the counts.
  Census census(const Eigen::VectorXd& x) const;
  // Adds `rings` rings of faces (sharing a vertex) around the faces in in_region.
  void dilate(std::vector<char>& in_region, int rings) const;
  // Marks the faces around vertices wound a full turn off their cone as wound (bad) faces.
  void mark_wound(const Eigen::VectorXd& x, Census& cs) const;
  // Vertices off their cone angle whose faces are all positive.
  std::vector<int> wound_vertices(const std::vector<int>& charge, const Census& cs) const;
  // Faces around the wound vertices, grown until each cluster's turns cancel.
  std::vector<char> wound_region(const std::vector<int>& defects, const std::vector<int>& charge) const;
  // Connected parts of region (faces sharing a vertex): part per face (-1 outside), *count parts.
  std::vector<int> region_parts(const std::vector<char>& region, int* count) const;

  // Whether the equality-only optimum needs the regularity repair.
  bool needs_repair(const Census& initial) const;
  // More bad faces at the start than the caller lets the repair take on.
  bool declines_repair(const Census& initial) const;
  // The repair rounds (local; local again moving shared coordinates; global in the field's frame
  // and local again), then re-linearization.
  void repair();
  // Lets the local repair move shared coordinates (System::shared_var) from now on; true when
  // bad faces are left and some shared coordinate reaches one of them.
  bool start_moving_shared_coordinates();
  // One global solve in the field's frame; true when local repair rounds should follow.
  bool field_frame_solve();
  // Local repair rounds (at most max_rounds) from the current bad faces; ends at the best pose.
  void local_repair(int max_rounds);
  // One local repair round (repair_step), its bad faces and time recorded; false when the repair
  // should stop.
  bool repair_round(int round, RepairTrack& track);
  bool repair_step(int round, RepairTrack& track);
  // A stagnation bound of options_ holds after `round` (no new best, no fewer bad faces, no fewer
  // bad faces over regions of most of the mesh).
  bool stagnates(int round, const RepairTrack& track) const;
  // options_.halving_rounds > 0 and the bad faces have not halved over that many rounds.
  bool stops_halving() const;
  // `round` begins a plateau of the bad faces and options_.caller_finishes takes the best pose.
  bool caller_finishes(int round, const RepairTrack& track);
  // The map of free variables x.
  Parametrization pose(const Eigen::VectorXd& x) const;
  // Constrains faces that went bad outside the constrained set; true when `next` is rejected.
  bool reject_escaped(const Census& next);
  // Faces still bad get wider rings; the region and the constrained set grow accordingly.
  void widen_rings();
  // Region: each bad face with its own number of rings.
  void grow_region();
  // Adds the bad faces of cs (only those outside *only_outside if given) with `rings` rings to set.
  void add_bad(const Census& cs, std::vector<char>& set, int rings, const std::vector<char>* only_outside) const;
  // Re-linearization rounds around the regular pose.
  void relinearize();

  // One Ipopt solve of the region; returns x with the region's variables replaced.
  Eigen::VectorXd solve_region(const std::vector<char>& in_region, const std::vector<char>& active,
                               const Eigen::VectorXd& x, const Census& cs, int strategy, double pb, double pe,
                               QPResult::Status* status);
  // Whether variable v moves in a region: all its faces lie in it (or, a shared coordinate once
  // move_shared_ is set, one of them does).
  bool moves_in_region(int v, const std::vector<char>& in_region) const;
  // Variable v is shared and regions move shared variables now.
  bool moves_shared(int v) const { return move_shared_ && sys_.shared_var[v]; }
  // The region's variables and the faces they reach that get constraints.
  RegionQP select_region(const std::vector<char>& in_region, const std::vector<char>& active);
  // Rotation of face g's ideal shape that best fits its shape in x.
  Vec2 best_fit(const Eigen::VectorXd& x, int g) const;
  // Rotations of the reference shapes of the constrained faces without a valid reference.
  std::vector<Vec2> reference_rotations(const std::vector<int>& faces, const Eigen::VectorXd& x, const Census& cs,
                                        bool follow_neighbours) const;
  // Rotation of bad face f; healthy neighbours join the first layer when it propagates.
  void seed_rotation(int f, const Eigen::VectorXd& x, const Census& cs, bool follow_neighbours,
                     ReferenceRotations& rr) const;
  // Spreads the rotations inward through the bad faces, layer by layer.
  void propagate_rotations(const Census& cs, ReferenceRotations& rr) const;
  // Hessian, linear term and start of the objective over the region's variables (others fixed).
  void add_objective(RegionQP& rq, const Eigen::VectorXd& x) const;
  // Reference triangle of face f (corner k at r[k]).
  void reference_triangle(int f, const Eigen::VectorXd& x, const Census& cs, int strategy, const Vec2& rotation,
                          Vec2 r[3]) const;
  // The caller's pose of face f in r; true when it is healthy there.
  bool caller_reference(int f, Vec2 r[3]) const;
  // Face f's pose in x with one vertex moved to the positive side; true when it is positive.
  bool unfolded_reference(int f, const Eigen::VectorXd& x, Vec2 r[3]) const;
  // Face f's ideal shape rotated by `rotation`.
  void rotated_ideal(int f, const Vec2& rotation, Vec2 r[3]) const;
  // Tri-sector constraint rows of face f around reference triangle r.
  void add_sector_constraints(int f, const Vec2 r[3], const Eigen::VectorXd& x, const Census& cs, int strategy,
                              RegionQP& rq) const;
  // Slack variables of the elastic rows, and the constraint matrix.
  void finish_constraints(RegionQP& rq) const;
  // Runs Ipopt on the QP; returns x with the region's variables replaced by the solution.
  Eigen::VectorXd run_ipopt(const RegionQP& rq, const Eigen::VectorXd& x, double pb, double pe,
                            QPResult::Status* status);

  const ParametrizationProblem& problem_;
  const TriMesh& mesh_;
  const std::vector<Vec2>& ideal_;
  const std::vector<double>& ideal_area_;
  System& sys_;
  const ParametrizationSolveOptions& options_;
  Progress& progress_;
  ParametrizationSolution& out_;
  ParametrizationSolveStats& st_;
  const Evaluator ev_;
  const int nf_, nc_;
  const double pb_, span_;  // the caller's progress range: begin and length

  std::vector<int> vf_start_, vf_;     // vertex -> faces
  std::vector<Vec2> pinned_rotation_;  // #F, see find_isoline_rotations
  std::vector<char> iso_halfedge_;     // 3#F: halfedges on isolines
  Eigen::VectorXd z_;                  // the current pose (free variables)
  Census current_;                     // its faces
  // Active set: the variables of a region around the bad faces move; the bad faces and one ring
  // around them are constrained. Faces that turn bad outside the constrained set join it.
  std::vector<char> region_, active_;
  std::vector<int> rings_;     // #F per-face ring count (see repair)
  std::vector<char> touched_;  // faces that were bad at some point
  bool move_shared_ = false;   // regions move shared coordinates (see start_moving_shared_coordinates)
  int first_rings_ = 0, max_rings_ = 0, rounds_ = 1;
};

ParametrizationProblem::Solver::Solver(const ParametrizationProblem& problem, System& sys,
                                       const ParametrizationSolveOptions& options, Progress& progress,
                                       ParametrizationSolution& out)
    : problem_(problem),
      mesh_(problem.mesh_),
      ideal_(problem.ideal_),
      ideal_area_(problem.ideal_area_),
      sys_(sys),
      options_(options),
      progress_(progress),
      out_(out),
      st_(out.stats),
      ev_{problem.mesh_, problem.wedge_of_, sys.form_start, sys.form_var, sys.form_coeff, sys.form_const},
      nf_(problem.mesh_.num_faces()),
      nc_(3 * nf_),
      pb_(options.progress_begin),
      span_(options.progress_end - options.progress_begin),
      region_(nf_, 0),
      active_(nf_, 0) {}

void ParametrizationProblem::Solver::run() {
  record_system_stats();
  report(0.15);
  solve_equality_only();
  report(0.3);
  index_vertex_faces();
  current_ = census(z_);
  record_initial_stats();
  find_isoline_rotations();
  st_.repair_declined = declines_repair(current_);
  if (!st_.repair_declined && needs_repair(current_)) repair();
  report(1.0);
  write_output();
}

void ParametrizationProblem::Solver::report(double t) const {
  progress_.update(options_.progress_begin + t * (options_.progress_end - options_.progress_begin));
}

void ParametrizationProblem::Solver::record_system_stats() {
  st_.free_variables = sys_.num_free;
  st_.non_integer_pivots = sys_.non_integer_pivots;
  st_.redundant_constraints = sys_.redundant;
  st_.inconsistent_constraints = sys_.inconsistent;
}

void ParametrizationProblem::Solver::solve_equality_only() {
  Timer timer;
  z_ = Eigen::VectorXd::Zero(sys_.num_free);
  if (sys_.num_free > 0) {
    if (!sys_.factorized) {
      pin_blas_kernels();
      sys_.cholesky.compute(sys_.Q);
      if (sys_.cholesky.info() != Eigen::Success)
        throw Error(ErrorCode::StageFailed,
                    "parametrization: the energy is not positive definite (a part of the mesh is unconstrained)");
      sys_.factorized = true;
    }
    z_ = sys_.cholesky.solve(sys_.c);
    if (sys_.cholesky.info() != Eigen::Success || !z_.allFinite())
      throw Error(ErrorCode::StageFailed, "parametrization: the sparse Cholesky solve failed");
  }
  st_.seconds_cholesky = timer.seconds();
}

void ParametrizationProblem::Solver::index_vertex_faces() {
  vf_start_.assign(mesh_.num_vertices() + 1, 0);
  for (int c = 0; c < nc_; ++c) ++vf_start_[mesh_.F(c / 3, c % 3) + 1];
  for (int v = 0; v < mesh_.num_vertices(); ++v) vf_start_[v + 1] += vf_start_[v];
  vf_.resize(nc_);
  std::vector<int> fill(vf_start_.begin(), vf_start_.end() - 1);
  for (int c = 0; c < nc_; ++c) vf_[fill[mesh_.F(c / 3, c % 3)]++] = c / 3;
}

void ParametrizationProblem::Solver::record_initial_stats() {
  {
    Parametrization initial;
    initial.uv.resize(nc_, 2);
    for (int c = 0; c < nc_; ++c) initial.uv.row(c) = ev_.corner(z_, c).transpose();
    st_.energy_initial = problem_.field_energy(initial);
  }
  st_.flipped_initial = current_.flipped;
  st_.degenerate_initial = current_.degenerate;
  st_.thin_initial = current_.thin;
  st_.forced_degenerate = current_.forced;
}

void ParametrizationProblem::Solver::find_isoline_rotations() {
  pinned_rotation_.assign(nf_, Vec2::Zero());
  iso_halfedge_.assign(nc_, 0);
  for (const auto& [h, axis] : problem_.isolines_) {
    for (int side : {h, mesh_.opposite[h]}) {
      if (side < 0) continue;
      iso_halfedge_[side] = 1;
      const int f = side / 3;
      const int a = side == h ? axis : (axis + problem_.rotation_[h]) % 2;
      const Vec2 d = ideal_[TriMesh::next(side)] - ideal_[side];
      const double angle = std::atan2(d.y(), d.x());
      const double base = a == 0 ? M_PI / 2 : 0.0;             // u constant: the edge runs along v
      const double turn = std::remainder(base - angle, M_PI);  // nearest of base, base + pi
      pinned_rotation_[f] += Vec2(std::cos(turn), std::sin(turn));
    }
  }
  for (Vec2& r : pinned_rotation_)
    if (r.squaredNorm() > 0) r.normalize();
}

Parametrization ParametrizationProblem::Solver::pose(const Eigen::VectorXd& x) const {
  Parametrization p;
  p.uv.resize(nc_, 2);
  for (int c = 0; c < nc_; ++c) p.uv.row(c) = ev_.corner(x, c).transpose();
  p.rotation = problem_.rotation_;
  p.is_cut = problem_.is_cut_;
  return p;
}

void ParametrizationProblem::Solver::write_output() {
  out_.param = pose(z_);
  const Parametrization& p = out_.param;
  st_.flipped = current_.flipped;
  st_.degenerate = current_.degenerate;
  st_.winding_defects = problem_.winding_defects(p);
  st_.thin = current_.thin;
  st_.min_area_ratio = current_.min_ratio;
  st_.energy = problem_.field_energy(p);
  st_.constraint_violation = problem_.constraint_violation(p);
  st_.moved_shared_coordinates = move_shared_;
}

FaceState ParametrizationProblem::Solver::classify_face(const Eigen::VectorXd& x, int f, double* ratio) const {
  const Vec2 a = ev_.corner(x, 3 * f), b = ev_.corner(x, 3 * f + 1), c = ev_.corner(x, 3 * f + 2);
  const double area = 0.5 * cross2(b - a, c - a);
  if (ratio) *ratio = area / ideal_area_[f];
  if (sys_.forced_degenerate[f]) return kForced;
  const int s = orient2d_sign(a, b, c);
  if (s < 0) return kFlipped;
  if (s == 0) return kDegenerate;
  return area < options_.min_area_ratio * ideal_area_[f] ? kThin : kHealthy;
}

Census ParametrizationProblem::Solver::census(const Eigen::VectorXd& x) const {
  Census cs;
  cs.state.resize(nf_);
  cs.min_ratio = std::numeric_limits<double>::infinity();
  for (int f = 0; f < nf_; ++f) {
    double ratio = 0;
    cs.state[f] = classify_face(x, f, &ratio);
    cs.min_ratio = std::min(cs.min_ratio, ratio);
    cs.flipped += cs.state[f] == kFlipped;
    cs.degenerate += cs.state[f] == kDegenerate || cs.state[f] == kForced;
    cs.forced += cs.state[f] == kForced;
    cs.thin += cs.state[f] == kThin;
    if (cs.state[f] != kHealthy && cs.state[f] != kForced) cs.depth += std::max(0.0, options_.min_area_ratio - ratio);
  }
  mark_wound(x, cs);
  return cs;
}

void ParametrizationProblem::Solver::dilate(std::vector<char>& in_region, int rings) const {
  std::vector<int> frontier;
  for (int f = 0; f < nf_; ++f)
    if (in_region[f]) frontier.push_back(f);
  for (int r = 0; r < rings && !frontier.empty(); ++r) {
    std::vector<int> next;
    for (int f : frontier)
      for (int k = 0; k < 3; ++k) {
        const int v = mesh_.F(f, k);
        for (int i = vf_start_[v]; i < vf_start_[v + 1]; ++i)
          if (!in_region[vf_[i]]) in_region[vf_[i]] = 1, next.push_back(vf_[i]);
      }
    frontier.swap(next);
  }
}

// A flip-free map can still wind a one-ring a full turn off its cone (a valence-5 cone wound by
// 90 degrees); the quads would then have a wrong irregular vertex there. Such vertices, with
// rings around them until each cluster's turns cancel (up to 8 rings), become bad faces whose
// references follow the field (never their own wound pose).
void ParametrizationProblem::Solver::mark_wound(const Eigen::VectorXd& x, Census& cs) const {
  cs.wound.assign(nf_, 0);
  if (problem_.cone_quarter_turns_.empty() || !options_.winding_repair) return;
  const std::vector<int> charge = problem_.winding_charges([&](int c) { return ev_.corner(x, c); });
  const std::vector<int> defects = wound_vertices(charge, cs);
  if (defects.empty()) return;
  const std::vector<char> region = wound_region(defects, charge);
  for (int f = 0; f < nf_; ++f) {
    if (!region[f] || cs.state[f] == kForced) continue;
    cs.wound[f] = 1;
    if (cs.state[f] == kHealthy) cs.state[f] = kWound, ++cs.wound_faces;
  }
}

std::vector<int> ParametrizationProblem::Solver::wound_vertices(const std::vector<int>& charge,
                                                                const Census& cs) const {
  std::vector<int> defects;
  for (int v = 0; v < mesh_.num_vertices(); ++v) {
    if (charge[v] == 0 || vf_start_[v] == vf_start_[v + 1]) continue;
    bool clean = true;  // angles next to flipped faces say little; the global pass handles those
    for (int i = vf_start_[v]; i < vf_start_[v + 1] && clean; ++i)
      clean = cs.state[vf_[i]] == kHealthy || cs.state[vf_[i]] == kThin;
    if (clean) defects.push_back(v);
  }
  return defects;
}

std::vector<char> ParametrizationProblem::Solver::wound_region(const std::vector<int>& defects,
                                                               const std::vector<int>& charge) const {
  std::vector<char> region(nf_, 0);
  for (int v : defects)
    for (int i = vf_start_[v]; i < vf_start_[v + 1]; ++i) region[vf_[i]] = 1;
  dilate(region, 1);
  for (int grow = 0; grow < 8; ++grow) {
    // Connected parts of the region (faces sharing a vertex) and their total turns.
    int num_parts = 0;
    const std::vector<int> part = region_parts(region, &num_parts);
    std::vector<int> turns(num_parts, 0);
    for (int v : defects) turns[part[vf_[vf_start_[v]]]] += charge[v];
    std::vector<char> seed(nf_, 0);
    bool any = false;
    for (int f = 0; f < nf_; ++f)
      if (region[f] && turns[part[f]] != 0) seed[f] = 1, any = true;
    if (!any) break;
    dilate(seed, 1);
    for (int f = 0; f < nf_; ++f) region[f] = region[f] || seed[f];
  }
  return region;
}

std::vector<int> ParametrizationProblem::Solver::region_parts(const std::vector<char>& region, int* count) const {
  std::vector<int> part(nf_, -1);
  *count = 0;
  for (int f0 = 0; f0 < nf_; ++f0) {
    if (!region[f0] || part[f0] >= 0) continue;
    const int id = (*count)++;
    std::vector<int> stack{f0};
    part[f0] = id;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const int v = mesh_.F(f, k);
        for (int i = vf_start_[v]; i < vf_start_[v + 1]; ++i)
          if (region[vf_[i]] && part[vf_[i]] < 0) part[vf_[i]] = id, stack.push_back(vf_[i]);
      }
    }
  }
  return part;
}

bool ParametrizationProblem::Solver::declines_repair(const Census& initial) const {
  return initial.bad() > options_.max_bad_share_to_repair * nf_;
}

bool ParametrizationProblem::Solver::needs_repair(const Census& initial) const {
  if (options_.skip_repair_if_forced && initial.forced > 0) return false;
  return options_.regularity != RegularityMode::Off &&
         (options_.regularity == RegularityMode::AllFaces || initial.bad() > 0);
}

void ParametrizationProblem::Solver::repair() {
  // Per-face ring count: starts at ring_size and doubles (up to max_ring_size) each round the
  // face is still bad, so that only stubborn clusters get large regions.
  first_rings_ = std::max(0, options_.ring_size);
  max_rings_ = std::max(options_.max_ring_size, first_rings_);
  rings_.assign(nf_, 0);
  rounds_ = std::max(1, options_.max_repair_rounds);
  touched_.assign(nf_, 0);
  // Each escalation is followed by half the rounds again.
  local_repair(rounds_);
  if (!st_.finished_by_caller && start_moving_shared_coordinates()) local_repair(std::max(1, rounds_ / 2));
  if (!st_.finished_by_caller && field_frame_solve()) local_repair(std::max(1, rounds_ / 2));
  // Re-linearize around the faces that were repaired.
  if (options_.regularity != RegularityMode::AllFaces) {
    region_ = touched_;
    dilate(region_, std::max(0, options_.ring_size));
  }
  relinearize();
}

// A local region moves only the variables whose faces all lie in it. After the elimination one
// variable can be in the coordinates of many vertices: the constant coordinate of an isoline
// along a whole feature curve or boundary, or a wedge at a cut arc's end, in terms of which the
// arc's far side is written. Faces whose flip needs such a variable to move stay bad in every
// local region (fandisk and mnf07 with sharp edges at 60 degrees: 2 and 5 such flips; the global solve
// then took 2 and 6 s). From here on a region moves a shared variable as soon as it holds one of
// its faces, and every face the variable reaches is constrained.
bool ParametrizationProblem::Solver::start_moving_shared_coordinates() {
  if (current_.bad() == 0 || move_shared_ || !options_.move_shared_coordinates) return false;
  std::vector<char> near_bad(nf_, 0);
  add_bad(current_, near_bad, max_rings_, nullptr);
  for (int v = 0; v < sys_.num_free; ++v) {
    if (!sys_.shared_var[v]) continue;
    for (int i = sys_.var_face_start[v]; i < sys_.var_face_start[v + 1]; ++i)
      if (near_bad[sys_.var_face[i]]) return move_shared_ = true;
  }
  return false;
}

// The local repair left bad faces (typically a flip next to a wound vertex, which no local
// region can unwind): one global solve with every face held in the sectors of its ideal shape in
// the field's frame (Bommes et al. 2013), elastically; then local repair again.
bool ParametrizationProblem::Solver::field_frame_solve() {
  if (current_.bad() == 0 || problem_.cone_quarter_turns_.empty() || options_.regularity == RegularityMode::AllFaces ||
      !options_.winding_repair || !options_.field_frame_solve)
    return false;
  Census all = current_;
  all.field_frame = true;
  for (int f = 0; f < nf_; ++f)
    if (all.state[f] == kHealthy) all.state[f] = kWound;
  const std::vector<char> every(nf_, 1);
  QPResult::Status status;
  const double t0 = 0.3 + 0.5 * std::min(st_.repair_rounds, rounds_ - 1) / rounds_;
  const Eigen::VectorXd y =
      solve_region(every, every, z_, all, kPropagated, pb_ + span_ * t0, pb_ + span_ * (t0 + 0.5 / rounds_), &status);
  ++st_.field_frame_solves;
  Census next = census(y);
  if (!(next.bad() < current_.bad())) return false;
  z_ = y;
  current_ = std::move(next);
  rings_.assign(nf_, 0);
  active_.assign(nf_, 1);  // every face the repair's variables reach stays constrained
  return current_.bad() != 0;
}

void ParametrizationProblem::Solver::local_repair(int max_rounds) {
  for (int f = 0; f < nf_; ++f)
    if (is_bad(current_.state[f])) rings_[f] = first_rings_;
  if (options_.regularity == RegularityMode::AllFaces) {
    region_.assign(nf_, 1);
    active_.assign(nf_, 1);
  } else {
    grow_region();
    add_bad(current_, active_, 1, nullptr);
  }
  for (int f = 0; f < nf_; ++f) touched_[f] = touched_[f] || is_bad(current_.state[f]);
  RepairTrack track{current_, z_};
  for (int round = 0; round < max_rounds; ++round)
    if (!repair_round(round, track)) break;
  z_ = track.best_z;
  current_ = track.best;
}

bool ParametrizationProblem::Solver::repair_round(int round, RepairTrack& track) {
  Timer timer;
  const bool more = repair_step(round, track);
  st_.bad_after_round.push_back(current_.bad());
  st_.seconds_of_round.push_back(timer.seconds());
  return more;
}

bool ParametrizationProblem::Solver::repair_step(int round, RepairTrack& track) {
  ++st_.repair_rounds;
  QPResult::Status status;
  const double t0 = 0.3 + 0.5 * std::min(st_.repair_rounds - 1, rounds_ - 1) / rounds_;
  // The strategies take turns (a rejected round leaves the pose unchanged).
  static const int kOrder[4] = {kUnfold, kOwnFit, kPropagated, kAllElastic};
  const int strategy = kOrder[round % 4];
  const int region_faces = nf_ - static_cast<int>(std::count(region_.begin(), region_.end(), 0));
  const Eigen::VectorXd y = solve_region(region_, active_, z_, current_, strategy, pb_ + span_ * t0,
                                         pb_ + span_ * (t0 + 0.5 / rounds_), &status);
  Census next = census(y);
  if (reject_escaped(next)) return true;
  // Keep the new pose when it has fewer bad faces or they are less bad.
  const bool accepted = next.bad() < current_.bad() || next.depth < current_.depth;
  if (accepted) {
    z_ = y;
    current_ = std::move(next);
    track.rejected = 0;
    if (current_.bad() < track.best.bad()) track.fewer_bad_round = round;
    if (current_.bad() < track.best.bad() ||
        (current_.bad() == track.best.bad() && current_.depth < track.best.depth)) {
      track.best = current_;
      track.best_z = z_;
      track.best_round = round;
    }
  } else if (++track.rejected >= 4) {
    return false;  // no strategy makes progress: a fixed point
  }
  const bool wide = 2 * region_faces >= nf_;
  track.wide_rounds = track.fewer_bad_round == round ? 0 : track.wide_rounds + wide;
  if (current_.bad() == 0 || stagnates(round, track) || stops_halving() || caller_finishes(round, track)) return false;
  widen_rings();
  return true;
}

bool ParametrizationProblem::Solver::caller_finishes(int round, const RepairTrack& track) {
  if (!options_.caller_finishes || round != track.fewer_bad_round + 1) return false;
  st_.finished_by_caller = options_.caller_finishes(pose(track.best_z));
  return st_.finished_by_caller;
}

bool ParametrizationProblem::Solver::stagnates(int round, const RepairTrack& track) const {
  if (round - track.best_round >= options_.stagnation_rounds) return true;  // no new best for a while
  const int count = options_.count_stagnation_rounds, region = options_.region_stagnation_rounds;
  if (count > 0 && round - track.fewer_bad_round >= count) return true;  // no fewer bad faces for a while
  return region > 0 && track.wide_rounds >= region;                      // no fewer bad faces over most of the mesh
}

bool ParametrizationProblem::Solver::stops_halving() const {
  const int window = options_.halving_rounds;
  const std::vector<int>& before = st_.bad_after_round;  // the rounds before this one
  if (window <= 0 || static_cast<int>(before.size()) < window) return false;
  return 2 * current_.bad() > before[before.size() - window];
}

bool ParametrizationProblem::Solver::reject_escaped(const Census& next) {
  bool escaped = false;
  for (int f = 0; f < nf_ && !escaped; ++f) escaped = is_bad(next.state[f]) && !active_[f];
  if (!escaped) return false;
  // Unconstrained faces went bad: they are constrained from now on. The new pose is kept only if
  // it is better anyway.
  for (int f = 0; f < nf_; ++f)
    if (is_bad(next.state[f]) && !active_[f]) {
      touched_[f] = 1;
      if (rings_[f] == 0) rings_[f] = first_rings_;
    }
  add_bad(next, active_, 1, &active_);
  if (next.bad() < current_.bad() && next.depth < current_.depth) return false;
  add_bad(next, region_, first_rings_, nullptr);
  return true;
}

void ParametrizationProblem::Solver::widen_rings() {
  // Faces still bad get wider rings; faces fixed earlier stay constrained.
  for (int f = 0; f < nf_; ++f)
    if (is_bad(current_.state[f])) {
      rings_[f] = rings_[f] == 0 ? first_rings_ : std::min(std::max(1, 2 * rings_[f]), max_rings_);
      touched_[f] = 1;
    }
  if (options_.regularity != RegularityMode::AllFaces) grow_region();
  add_bad(current_, active_, 1, nullptr);
}

void ParametrizationProblem::Solver::grow_region() {
  region_.assign(nf_, 0);
  std::vector<int> levels;
  for (int f = 0; f < nf_; ++f)
    if (is_bad(current_.state[f])) levels.push_back(rings_[f]);
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  for (int level : levels) {
    std::vector<char> seed(nf_, 0);
    for (int f = 0; f < nf_; ++f) seed[f] = is_bad(current_.state[f]) && rings_[f] == level;
    dilate(seed, level);
    for (int f = 0; f < nf_; ++f) region_[f] = region_[f] || seed[f];
  }
}

void ParametrizationProblem::Solver::add_bad(const Census& cs, std::vector<char>& set, int rings,
                                             const std::vector<char>* only_outside) const {
  std::vector<char> seed(nf_, 0);
  for (int f = 0; f < nf_; ++f) seed[f] = is_bad(cs.state[f]) && (!only_outside || !(*only_outside)[f]);
  dilate(seed, rings);
  for (int f = 0; f < nf_; ++f) set[f] = set[f] || seed[f];
}

// Re-linearization around the regular pose (paper §7.1): lowers the energy within the region
// while every constraint set contains the current pose.
void ParametrizationProblem::Solver::relinearize() {
  if (current_.bad() != 0 || options_.relinearization_rounds <= 0) return;
  double value = objective(z_);
  for (int round = 0; round < options_.relinearization_rounds; ++round) {
    QPResult::Status status;
    const double t0 = 0.8 + 0.2 * round / options_.relinearization_rounds;
    // Every constrained face is healthy here: the strategy (for bad faces) plays no part.
    const Eigen::VectorXd y = solve_region(region_, active_, z_, current_, kUnfold, pb_ + span_ * t0,
                                           pb_ + span_ * (t0 + 0.2 / options_.relinearization_rounds), &status);
    Census next = census(y);
    const double next_value = objective(y);
    if (next.bad() > 0 || !(next_value < value)) break;
    ++st_.relinearizations;
    const double drop = (value - next_value) / std::max(value, 1e-300);
    z_ = y;
    current_ = std::move(next);
    value = next_value;
    if (drop < options_.relinearization_tolerance) break;
  }
}

// One Ipopt solve over the variables of the region's corners; every face those variables reach
// gets tri-sector constraints linearized around its reference triangle (see RepairStrategy).
Eigen::VectorXd ParametrizationProblem::Solver::solve_region(const std::vector<char>& in_region,
                                                             const std::vector<char>& active, const Eigen::VectorXd& x,
                                                             const Census& cs, int strategy, double pb, double pe,
                                                             QPResult::Status* status) {
  const bool follow_neighbours = strategy == kPropagated || strategy == kAllElastic;
  RegionQP rq = select_region(in_region, active);
  const std::vector<Vec2> ref_rotation = reference_rotations(rq.faces, x, cs, follow_neighbours);
  add_objective(rq, x);
  for (int f : rq.faces) {
    Vec2 r[3];
    reference_triangle(f, x, cs, strategy, ref_rotation[f], r);
    add_sector_constraints(f, r, x, cs, strategy, rq);
  }
  finish_constraints(rq);
  return run_ipopt(rq, x, pb, pe, status);
}

RegionQP ParametrizationProblem::Solver::select_region(const std::vector<char>& in_region,
                                                       const std::vector<char>& active) {
  // Variables used only by region faces move; the active faces they reach are constrained.
  // A shared coordinate moved by move_shared_ constrains every face it reaches.
  RegionQP rq;
  rq.local.assign(sys_.num_free, -1);
  for (int v = 0; v < sys_.num_free; ++v)
    if (moves_in_region(v, in_region)) rq.local[v] = static_cast<int>(rq.vars.size()), rq.vars.push_back(v);
  std::vector<char> constrained(nf_, 0);
  for (int v : rq.vars) {
    const bool shared = moves_shared(v);
    for (int i = sys_.var_face_start[v]; i < sys_.var_face_start[v + 1]; ++i) {
      const int f = sys_.var_face[i];
      if ((active[f] || shared) && !constrained[f] && !sys_.forced_degenerate[f])
        constrained[f] = 1, rq.faces.push_back(f);
    }
  }
  st_.max_region_faces = std::max(st_.max_region_faces, static_cast<int>(rq.faces.size()));
  st_.max_qp_variables = std::max(st_.max_qp_variables, static_cast<int>(rq.vars.size()));
  return rq;
}

bool ParametrizationProblem::Solver::moves_in_region(int v, const std::vector<char>& in_region) const {
  // A shared variable moves at its first face inside, any other stops at its first face outside.
  const bool shared = moves_shared(v);
  const int begin = sys_.var_face_start[v], end = sys_.var_face_start[v + 1];
  for (int i = begin; i < end; ++i)
    if ((in_region[sys_.var_face[i]] != 0) == shared) return shared;
  return !shared && begin < end;
}

Vec2 ParametrizationProblem::Solver::best_fit(const Eigen::VectorXd& x, int g) const {
  double re = 0, im = 0;
  for (int k = 0; k < 3; ++k) {
    const Vec2 a = ideal_[3 * g + (k + 1) % 3] - ideal_[3 * g + k];
    const Vec2 b = ev_.corner(x, 3 * g + (k + 1) % 3) - ev_.corner(x, 3 * g + k);
    re += a.dot(b);
    im += cross2(a, b);
  }
  const double len = std::hypot(re, im);
  return len > 0 ? Vec2(re / len, im / len) : Vec2(1, 0);
}

// Faces without a valid reference use their ideal (isometric, field-aligned) shape rotated by the
// best-fit rotation of ideal onto current shape: their own, or (follow_neighbours) one propagated
// inward from the healthy faces around each bad cluster, so that adjacent bad faces agree. A
// rotation relative to the field is the same in every chart (rotations commute with the
// transitions), so it is carried across cuts unchanged.
std::vector<Vec2> ParametrizationProblem::Solver::reference_rotations(const std::vector<int>& faces,
                                                                      const Eigen::VectorXd& x, const Census& cs,
                                                                      bool follow_neighbours) const {
  ReferenceRotations rr;
  rr.rotation.assign(nf_, Vec2(1, 0));
  rr.assigned.assign(nf_, 0);
  for (int f : faces)
    if (cs.state[f] != kHealthy) seed_rotation(f, x, cs, follow_neighbours, rr);
  propagate_rotations(cs, rr);
  return std::move(rr.rotation);
}

void ParametrizationProblem::Solver::seed_rotation(int f, const Eigen::VectorXd& x, const Census& cs,
                                                   bool follow_neighbours, ReferenceRotations& rr) const {
  const Vec2& pinned = pinned_rotation_[f];
  // The global field-frame solve: the field's own frame (or the isoline's axis).
  if (cs.field_frame) {
    rr.rotation[f] = pinned.squaredNorm() > 0 ? pinned : Vec2(1, 0);
    rr.assigned[f] = 1;
    return;
  }
  // An isoline edge fixes the rotation: its direction is exactly an axis. Wound faces always
  // take their rotation from the healthy faces around their cluster.
  const bool propagate = follow_neighbours || cs.wound[f];
  if (pinned.squaredNorm() > 0) {
    rr.rotation[f] = pinned;
    rr.assigned[f] = 1;
  } else {
    rr.rotation[f] = best_fit(x, f);
    rr.assigned[f] = !propagate;
  }
  if (!propagate) return;
  if (pinned.squaredNorm() > 0) rr.layer.push_back(f);
  for (int k = 0; k < 3; ++k) {
    const int o = mesh_.opposite[3 * f + k];
    if (o >= 0 && cs.state[o / 3] == kHealthy && !rr.assigned[o / 3]) {
      rr.assigned[o / 3] = 1;
      rr.rotation[o / 3] = best_fit(x, o / 3);
      rr.layer.push_back(o / 3);
    }
  }
}

void ParametrizationProblem::Solver::propagate_rotations(const Census& cs, ReferenceRotations& rr) const {
  while (!rr.layer.empty()) {
    std::vector<int> next;
    for (int g : rr.layer)
      for (int k = 0; k < 3; ++k) {
        const int o = mesh_.opposite[3 * g + k];
        if (o < 0 || rr.assigned[o / 3] || cs.state[o / 3] == kHealthy || cs.state[o / 3] == kForced) continue;
        const int f = o / 3;
        Vec2 sum = Vec2::Zero();
        for (int j = 0; j < 3; ++j) {
          const int p = mesh_.opposite[3 * f + j];
          if (p >= 0 && rr.assigned[p / 3]) sum += rr.rotation[p / 3];
        }
        if (sum.norm() > 0) rr.rotation[f] = sum.normalized();
        rr.assigned[f] = 1;
        next.push_back(f);
      }
    rr.layer.swap(next);
  }
}

void ParametrizationProblem::Solver::add_objective(RegionQP& rq, const Eigen::VectorXd& x) const {
  const int n = static_cast<int>(rq.vars.size());
  SparseQP& qp = rq.qp;
  std::vector<Triplet> ht;
  qp.linear.resize(n);
  for (int j = 0; j < n; ++j) {
    double fixed = 0;
    for (SpMat::InnerIterator it(sys_.Q, rq.vars[j]); it; ++it) {
      const int l = rq.local[it.row()];
      if (l >= 0)
        ht.emplace_back(l, j, 2 * it.value());
      else
        fixed += it.value() * x[it.row()];
    }
    qp.linear[j] = 2 * (fixed - sys_.c[rq.vars[j]]);
  }
  qp.hessian.resize(n, n);
  qp.hessian.setFromTriplets(ht.begin(), ht.end());
  qp.start.resize(n);
  for (int j = 0; j < n; ++j) qp.start[j] = x[rq.vars[j]];
}

// Current pose if healthy, else the caller's pose if healthy there, else (kUnfold) the current
// pose unfolded, else the ideal field-aligned shape rotated by `rotation`.
void ParametrizationProblem::Solver::reference_triangle(int f, const Eigen::VectorXd& x, const Census& cs, int strategy,
                                                        const Vec2& rotation, Vec2 r[3]) const {
  if (cs.state[f] == kHealthy) {
    for (int k = 0; k < 3; ++k) r[k] = ev_.corner(x, 3 * f + k);
    return;
  }
  if (options_.reference && !cs.wound[f] && caller_reference(f, r)) return;
  if (strategy == kUnfold && !cs.wound[f] && unfolded_reference(f, x, r)) return;
  rotated_ideal(f, rotation, r);
}

bool ParametrizationProblem::Solver::caller_reference(int f, Vec2 r[3]) const {
  for (int k = 0; k < 3; ++k) r[k] = options_.reference->corner(f, k);
  const double area = 0.5 * cross2(r[1] - r[0], r[2] - r[0]);
  return orient2d_sign(r[0], r[1], r[2]) > 0 && area >= options_.min_area_ratio * ideal_area_[f];
}

bool ParametrizationProblem::Solver::unfolded_reference(int f, const Eigen::VectorXd& x, Vec2 r[3]) const {
  // Move the vertex whose adjacent edges are no isolines and which is closest to the line of its
  // opposite edge, to the positive side with a modest area.
  for (int k = 0; k < 3; ++k) r[k] = ev_.corner(x, 3 * f + k);
  int best = -1;
  double best_height = 0;
  for (int k = 0; k < 3; ++k) {
    if (iso_halfedge_[3 * f + k] || iso_halfedge_[3 * f + (k + 2) % 3]) continue;
    const Vec2 d = r[(k + 2) % 3] - r[(k + 1) % 3];
    if (!(d.norm() > 0)) continue;
    const double height = std::abs(cross2(d, r[k] - r[(k + 1) % 3])) / d.norm();
    if (best < 0 || height < best_height) best = k, best_height = height;
  }
  if (best < 0) return false;
  const Vec2 a = r[(best + 1) % 3], d = r[(best + 2) % 3] - a;
  const double len = d.norm();
  const Vec2 dir = d / len, left(-dir.y(), dir.x());
  const double area = std::max(std::abs(0.5 * cross2(r[1] - r[0], r[2] - r[0])), 0.05 * ideal_area_[f]);
  r[best] = a + (r[best] - a).dot(dir) * dir + (2 * area / len) * left;
  return orient2d_sign(r[0], r[1], r[2]) > 0;
}

void ParametrizationProblem::Solver::rotated_ideal(int f, const Vec2& rotation, Vec2 r[3]) const {
  const double re = rotation.x(), im = rotation.y();
  const double angle = (re == 0 && im == 0) ? 0.0 : std::atan2(im, re);
  const double cosine = std::cos(angle), sine = std::sin(angle);
  for (int k = 0; k < 3; ++k) {
    const Vec2 q = ideal_[3 * f + k];
    r[k] = Vec2(cosine * q.x() - sine * q.y(), sine * q.x() + cosine * q.y());
  }
}

void ParametrizationProblem::Solver::add_sector_constraints(int f, const Vec2 r[3], const Eigen::VectorXd& x,
                                                            const Census& cs, int strategy, RegionQP& rq) const {
  const double ideal_len =
      ((ideal_[3 * f + 1] - ideal_[3 * f]).norm() + (ideal_[3 * f + 2] - ideal_[3 * f + 1]).norm() +
       (ideal_[3 * f] - ideal_[3 * f + 2]).norm()) /
      3;
  Vec2 bound[3];
  sector_bisectors(r, bound);
  for (int k = 0; k < 3; ++k) {
    const Vec2 e = r[(k + 1) % 3] - r[k];
    // cross(bound_k, e) >= m and cross(e, bound_{k+1}) >= m; in terms of e: n . e >= m.
    const Vec2 normals[2] = {Vec2(-bound[k].y(), bound[k].x()), Vec2(bound[(k + 1) % 3].y(), -bound[(k + 1) % 3].x())};
    for (const Vec2& nrm : normals) {
      const double ref_value = nrm.dot(e);
      const double margin = std::min(options_.margin * ideal_len, 0.5 * std::max(ref_value, 0.0));
      double bound_value = margin;
      const int ca = 3 * f + (k + 1) % 3, cb = 3 * f + k;  // e = p(ca) - p(cb)
      for (int a = 0; a < 2; ++a)
        for (int side = 0; side < 2; ++side) {
          const int v = ev_.var(side == 0 ? ca : cb, a);
          const double s = (side == 0 ? 1.0 : -1.0) * nrm[a];
          bound_value -= s * sys_.form_const[v];
          for (int i = sys_.form_start[v]; i < sys_.form_start[v + 1]; ++i) {
            const int gv = sys_.form_var[i];
            if (rq.local[gv] >= 0)
              rq.ct.emplace_back(rq.rows, rq.local[gv], s * sys_.form_coeff[i]);
            else
              bound_value -= s * sys_.form_coeff[i] * x[gv];
          }
        }
      rq.lower.push_back(bound_value);
      // Faces without a valid reference of their own may violate their sectors at a (large) cost,
      // so that the problem stays feasible; re-linearization continues.
      if (cs.state[f] != kHealthy || strategy == kAllElastic)
        rq.elastic.push_back({rq.rows, options_.elastic_weight * ideal_len});
      ++rq.rows;
    }
  }
}

void ParametrizationProblem::Solver::finish_constraints(RegionQP& rq) const {
  const int n = static_cast<int>(rq.vars.size()), ns = static_cast<int>(rq.elastic.size());
  SparseQP& qp = rq.qp;
  if (ns > 0) {
    // Slack s >= 0 per elastic row: a.x + s >= lower, cost weight * s.
    qp.hessian.conservativeResize(n + ns, n + ns);
    qp.linear.conservativeResize(n + ns);
    qp.start.conservativeResize(n + ns);
    qp.variable_lower = Eigen::VectorXd::Constant(n + ns, -2e19);
    for (int j = 0; j < ns; ++j) {
      rq.ct.emplace_back(rq.elastic[j].first, n + j, 1.0);
      qp.linear[n + j] = rq.elastic[j].second;
      qp.variable_lower[n + j] = 0;
    }
  }
  qp.constraints.resize(rq.rows, n + ns);
  qp.constraints.setFromTriplets(rq.ct.begin(), rq.ct.end());
  qp.lower = Eigen::Map<Eigen::VectorXd>(rq.lower.data(), rq.rows);
  if (ns > 0) {
    const Eigen::VectorXd value = qp.constraints.leftCols(n) * qp.start.head(n);
    for (int j = 0; j < ns; ++j) {
      const int r = rq.elastic[j].first;
      qp.start[n + j] = std::max(0.0, qp.lower[r] - value[r]);
    }
  }
}

Eigen::VectorXd ParametrizationProblem::Solver::run_ipopt(const RegionQP& rq, const Eigen::VectorXd& x, double pb,
                                                          double pe, QPResult::Status* status) {
  const int n = static_cast<int>(rq.vars.size()), ns = static_cast<int>(rq.elastic.size());
  QPOptions qo;
  qo.max_iterations = options_.max_ipopt_iterations;
  qo.tolerance = options_.ipopt_tolerance;
  qo.progress_begin = pb;
  qo.progress_end = pe;
  Timer t;
  const QPResult res = solve_qp(rq.qp, qo, progress_);
  st_.seconds_ipopt += t.seconds();
  ++st_.ipopt_solves;
  st_.qp_by_ipopt += res.by_ipopt;
  st_.ipopt_iterations += res.iterations;
  *status = res.status;
  Eigen::VectorXd y = x;
  if (res.status != QPResult::Status::Failed && res.x.size() == n + ns && res.x.allFinite())
    for (int j = 0; j < n; ++j) y[rq.vars[j]] = res.x[j];
  return y;
}

ParametrizationSolution ParametrizationProblem::solve(const ParametrizationSolveOptions& options, Progress& progress) {
  if (options.reference && (options.reference->uv.rows() != 3 * mesh_.num_faces()))
    throw Error(ErrorCode::InvalidArgument, "parametrization: the reference pose does not match the mesh");
  ParametrizationSolution out;
  Timer timer;
  System& sys = system(options.linear_constraints, options.penalty_weight, progress);
  out.stats.seconds_assembly = timer.seconds();
  Solver(*this, sys, options, progress, out).run();
  return out;
}

ParametrizationSolution ParametrizationProblem::solve_with_relinearization(ParametrizationSolveOptions options,
                                                                           double epsilon, int max_rounds,
                                                                           Progress& progress) {
  const double pb = options.progress_begin, span = options.progress_end - options.progress_begin;
  ParametrizationSolution last;
  Parametrization pose;
  bool have_pose = options.reference != nullptr;
  if (have_pose) pose = *options.reference;
  ParametrizationSolveStats total;
  auto accumulate = [&](const ParametrizationSolveStats& s) {
    total.ipopt_solves += s.ipopt_solves;
    total.ipopt_iterations += s.ipopt_iterations;
    total.qp_by_ipopt += s.qp_by_ipopt;
    total.repair_rounds += s.repair_rounds;
    total.field_frame_solves += s.field_frame_solves;
    total.moved_shared_coordinates = total.moved_shared_coordinates || s.moved_shared_coordinates;
    total.relinearizations += s.relinearizations;
    total.seconds_assembly += s.seconds_assembly;
    total.seconds_cholesky += s.seconds_cholesky;
    total.seconds_ipopt += s.seconds_ipopt;
  };
  const int rounds = std::max(0, max_rounds);
  for (int round = 0; round < rounds; ++round) {
    options.linear_constraints = ConstraintMode::Penalty;
    options.reference = have_pose ? &pose : nullptr;
    options.progress_begin = pb + span * 0.8 * round / rounds;
    options.progress_end = pb + span * 0.8 * (round + 1) / rounds;
    last = solve(options, progress);
    accumulate(last.stats);
    pose = last.param;
    have_pose = true;
    if (last.stats.constraint_violation <= epsilon) break;
  }
  options.linear_constraints = ConstraintMode::Hard;
  options.reference = have_pose ? &pose : nullptr;
  options.progress_begin = pb + span * 0.8;
  options.progress_end = pb + span;
  ParametrizationSolution final_solution = solve(options, progress);
  accumulate(final_solution.stats);
  const ParametrizationSolveStats& s = final_solution.stats;
  total.free_variables = s.free_variables;
  total.flipped_initial = s.flipped_initial;
  total.degenerate_initial = s.degenerate_initial;
  total.thin_initial = s.thin_initial;
  total.flipped = s.flipped;
  total.winding_defects = s.winding_defects;
  total.degenerate = s.degenerate;
  total.thin = s.thin;
  total.forced_degenerate = s.forced_degenerate;
  total.min_area_ratio = s.min_area_ratio;
  total.energy = s.energy;
  total.energy_initial = s.energy_initial;
  total.constraint_violation = s.constraint_violation;
  total.max_region_faces = s.max_region_faces;
  total.max_qp_variables = s.max_qp_variables;
  total.non_integer_pivots = s.non_integer_pivots;
  total.redundant_constraints = s.redundant_constraints;
  total.inconsistent_constraints = s.inconsistent_constraints;
  final_solution.stats = total;
  return final_solution;
}

}  // namespace qgp
