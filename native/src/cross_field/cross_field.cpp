#include "cross_field/cross_field.h"

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <cmath>
#include <complex>
#include <random>
#include <string>

#include "core/blas_kernels.h"
#include "core/error.h"
#include "cross_field/detail/singularity_edits.h"

namespace qgp {
namespace {

using Complex = std::complex<double>;
using ComplexSparse = Eigen::SparseMatrix<Complex>;
using ComplexVector = Eigen::VectorXcd;

constexpr double kQuarter = M_PI / 2;

// Angle reduced to (-pi, pi].
double wrap_angle(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

// Nearest multiple q of 90deg to angle a (ties round up); *residual = a - q * 90deg.
int nearest_quarter(double a, double* residual) {
  const double q = std::floor(a / kQuarter + 0.5);
  *residual = a - q * kQuarter;
  return static_cast<int>(q);
}

int mod4(int x) { return ((x % 4) + 4) % 4; }

// Per-face orthonormal frames and the angles of the halfedges in them.
struct FaceFrames {
  std::vector<Vec3> normal, e1, e2;  // #F unit vectors; e1 along halfedge 3f, e2 = normal x e1
  std::vector<double> area;          // #F
  std::vector<double> angle;         // 3#F: angle of halfedge h's vector in face(h)'s frame
};

FaceFrames compute_frames(const TriMesh& mesh) {
  const int nf = mesh.num_faces();
  FaceFrames fr;
  fr.normal.resize(nf), fr.e1.resize(nf), fr.e2.resize(nf), fr.area.resize(nf);
  fr.angle.resize(3 * nf);
  for (int f = 0; f < nf; ++f) {
    const Vec3 n = mesh.face_normal_unnormalized(f);
    const double len = n.norm(), e_len = mesh.edge_vector(3 * f).norm();
    if (!(len > 0) || !std::isfinite(len) || !(e_len > 0))
      throw Error(ErrorCode::InvalidMesh, "face " + std::to_string(f) + " has no normal (degenerate triangle)");
    fr.normal[f] = n / len;
    fr.area[f] = 0.5 * len;
    fr.e1[f] = mesh.edge_vector(3 * f) / e_len;
    fr.e2[f] = fr.normal[f].cross(fr.e1[f]);
    fr.angle[3 * f] = 0;
    for (int k = 1; k < 3; ++k) {
      const Vec3 v = mesh.edge_vector(3 * f + k);
      fr.angle[3 * f + k] = std::atan2(v.dot(fr.e2[f]), v.dot(fr.e1[f]));
    }
  }
  return fr;
}

bool is_feature_halfedge(const TriMesh& mesh, const std::vector<char>& feature_edge, int h) {
  return mesh.opposite[h] < 0 || feature_edge[mesh.edge_of[h]];
}

// Constraint of a face next to features (angle in its own frame), see the header:
// kAligned (one feature edge), kCornerCompromise (two or three feature edges), or free.
enum ConstraintKind : char { kFree = 0, kAligned = 1, kCornerCompromise = 2, kSectorCompromise = 3 };

ConstraintKind face_constraint(const TriMesh& mesh, const FaceFrames& fr, const std::vector<char>& feature_edge, int f,
                               double* theta) {
  bool is_feature[3];
  int count = 0;
  for (int k = 0; k < 3; ++k) count += is_feature[k] = is_feature_halfedge(mesh, feature_edge, 3 * f + k);
  if (count == 0) return kFree;
  if (count == 1) {
    for (int k = 0; k < 3; ++k)
      if (is_feature[k]) *theta = fr.angle[3 * f + k];
    return kAligned;
  }
  // Corner k lies between halfedge 3f+k (outgoing) and halfedge 3f+(k+2)%3 (incoming); both are
  // features there. With three features, take the corner closest to 90 degrees.
  int best = -1;
  double best_angle = 0;
  for (int k = 0; k < 3; ++k) {
    if (!is_feature[k] || !is_feature[(k + 2) % 3]) continue;
    const double beta = corner_angle(mesh, 3 * f + k);
    if (best < 0 || std::abs(beta - kQuarter) < std::abs(best_angle - kQuarter)) best = k, best_angle = beta;
  }
  // Outgoing edge at chart angle 45deg - beta/2, the other one at 45deg + beta/2.
  *theta = fr.angle[3 * f + best] + 0.5 * (best_angle - kQuarter);
  return kCornerCompromise;
}

// Acute sectors: around a vertex, the faces between two consecutive feature/boundary edges whose
// angles sum to beta < 45deg (over two faces or more) would otherwise map to zero quarter turns,
// i.e. collapse. All their faces get the compromise of a two-feature face: the first edge of the
// sector (counter-clockwise) at 45deg - beta/2 off its axis, the last at 45deg + beta/2, so the
// sector maps to exactly one quarter turn. A face in several acute sectors takes the sharpest;
// faces with two or three feature edges keep their own corner compromise.
void constrain_acute_sectors(const TriMesh& mesh, const FaceFrames& fr, const std::vector<char>& feature_edge,
                             std::vector<char>& kind, std::vector<double>& theta) {
  std::vector<double> sharpest(mesh.num_faces(), kQuarter / 2);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const std::vector<int> fan = outgoing_halfedges(mesh, v);
    const int k = static_cast<int>(fan.size());
    int start = -1, edges = 0;
    for (int j = 0; j < k; ++j)
      if (is_feature_halfedge(mesh, feature_edge, fan[j])) start = start < 0 ? j : start, ++edges;
    const bool boundary = is_boundary_vertex(mesh, v);
    if (start < 0 || (!boundary && edges < 2)) continue;  // a sector needs two distinct edges
    const int end = boundary ? k : start + k;
    for (int j0 = start; j0 < end;) {
      // Sector: faces fan[j0..j1] (cyclic), closed by the feature halfedge prev(fan[j1]).
      int j1 = j0;
      double beta = corner_angle(mesh, fan[j0 % k]);
      while (!is_feature_halfedge(mesh, feature_edge, TriMesh::prev(fan[j1 % k])))
        beta += corner_angle(mesh, fan[++j1 % k]);
      if (j1 > j0 && beta < kQuarter / 2) {
        double swept = 0;  // angle from the sector's first edge to fan[j]'s edge
        for (int j = j0; j <= j1; ++j) {
          const int h = fan[j % k], f = h / 3;
          if (kind[f] != kCornerCompromise && beta < sharpest[f]) {
            sharpest[f] = beta;
            kind[f] = kSectorCompromise;
            theta[f] = fr.angle[h] - swept + 0.5 * (beta - kQuarter);
          }
          swept += corner_angle(mesh, h);
        }
      }
      j0 = j1 + 1;
    }
  }
}

// Rotates v by the minimal rotation that takes unit vector a to unit vector b. For opposite
// vectors (a fold of 180 degrees) it turns by 180 degrees about `axis` (a unit vector orthogonal
// to both, e.g. the shared edge).
Vec3 rotate_between(const Vec3& a, const Vec3& b, const Vec3& v, const Vec3& axis = Vec3::Zero()) {
  const Vec3 k = a.cross(b);
  const double c = a.dot(b);
  if (1 + c > 1e-12) return v * c + k.cross(v) + k * (k.dot(v) / (1 + c));
  return 2 * axis.dot(v) * axis - v;
}

// Frames of the proxy surface that defines the connection: the true face normals diffused by one
// implicit heat step (M + t L) n = M n0 with t = r^2 / 2, r = kSmoothingRadius * bounding-box
// diagonal (L: face-adjacency Laplacian with the field's edge weights, cut at feature and
// boundary edges). Detail below ~1% of the model size (scan noise) then does not spawn
// singularity pairs, while coarse meshes (edges longer than r) are hardly changed. The field is
// solved in these frames and turned back onto the true faces by the minimal rotation between
// the normals.
constexpr double kSmoothingRadius = 0.01;

struct ProxyFrames {
  std::vector<Vec3> normal, e1, e2;  // #F unit vectors; e1 = halfedge 3f projected, e2 = normal x e1
};

ProxyFrames proxy_frames(const TriMesh& mesh, const FaceFrames& fr, const std::vector<char>& feature_edge) {
  const int nf = mesh.num_faces();
  const double r = kSmoothingRadius * mesh.bounding_box_diagonal();
  const double t = 0.5 * r * r;
  std::vector<Eigen::Triplet<double>> triplets;
  for (int f = 0; f < nf; ++f) triplets.emplace_back(f, f, fr.area[f]);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0 || feature_edge[e]) continue;
    const int f = h / 3, g = o / 3;
    const double w = t * 1.5 * mesh.edge_vector(h).squaredNorm() / (fr.area[f] + fr.area[g]);
    triplets.emplace_back(f, f, w);
    triplets.emplace_back(g, g, w);
    triplets.emplace_back(f, g, -w);
    triplets.emplace_back(g, f, -w);
  }
  Eigen::SparseMatrix<double> heat(nf, nf);
  heat.setFromTriplets(triplets.begin(), triplets.end());
  // Well conditioned (about 1 + 12 t / h^2 for edge length h): Jacobi-preconditioned CG.
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(1e-5);  // relative residual; the normals only steer the connection
  cg.setMaxIterations(1000);
  cg.compute(heat);
  Eigen::MatrixXd rhs(nf, 3);
  for (int f = 0; f < nf; ++f) rhs.row(f) = fr.area[f] * fr.normal[f].transpose();
  const Eigen::MatrixXd diffused = cg.solve(rhs);
  std::vector<Vec3> n(nf);
  for (int f = 0; f < nf; ++f) {
    const Vec3 d = diffused.row(f).transpose();
    n[f] = d.allFinite() && d.norm() > 0 ? Vec3(d.normalized()) : fr.normal[f];
  }
  ProxyFrames p;
  p.normal = std::move(n);
  p.e1.resize(nf), p.e2.resize(nf);
  for (int f = 0; f < nf; ++f) {
    // Where diffusion tilted a normal by 90 degrees or more (thin folds) keep the true one.
    if (!(p.normal[f].dot(fr.normal[f]) > 0)) p.normal[f] = fr.normal[f];
    p.e1[f] = rotate_between(fr.normal[f], p.normal[f], fr.e1[f]);
    p.e2[f] = p.normal[f].cross(p.e1[f]);
  }
  return p;
}

// Angle in frame (e1, e2) of the unit tangent obtained by turning angle t of frame (from_e1,
// from_e2, from_n) onto the plane with normal to_n.
double transfer_angle(double t, const Vec3& from_e1, const Vec3& from_e2, const Vec3& from_n, const Vec3& to_n,
                      const Vec3& e1, const Vec3& e2, const Vec3& fold_axis = Vec3::Zero()) {
  const Vec3 d = rotate_between(from_n, to_n, std::cos(t) * from_e1 + std::sin(t) * from_e2, fold_axis);
  return std::atan2(d.dot(e2), d.dot(e1));
}

// Dirichlet energy of the power field, sum over interior edges of w |z_g - rho z_f|^2, as a
// Hermitian matrix (full storage). rho: transport of the proxy frames across the edge (minimal
// rotation between the two proxy normals; on the true surface this is the rotation about the
// shared edge, i.e. unfolding).
ComplexSparse smoothness_matrix(const TriMesh& mesh, const FaceFrames& fr, const ProxyFrames& proxy) {
  std::vector<Eigen::Triplet<Complex>> triplets;
  triplets.reserve(4 * mesh.num_edges());
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0) continue;
    const int f = h / 3, g = o / 3;
    const double transport = transfer_angle(0, proxy.e1[f], proxy.e2[f], proxy.normal[f], proxy.normal[g], proxy.e1[g],
                                            proxy.e2[g], mesh.edge_vector(h).normalized());
    const Complex rho = std::polar(1.0, 4 * transport);
    const double w = 1.5 * mesh.edge_vector(h).squaredNorm() / (fr.area[f] + fr.area[g]);
    triplets.emplace_back(f, f, w);
    triplets.emplace_back(g, g, w);
    triplets.emplace_back(g, f, -w * rho);
    triplets.emplace_back(f, g, -w * std::conj(rho));
  }
  ComplexSparse A(mesh.num_faces(), mesh.num_faces());
  A.setFromTriplets(triplets.begin(), triplets.end());
  return A;
}

using Solver = Eigen::CholmodDecomposition<ComplexSparse, Eigen::Lower>;

// Ordering + symbolic analysis, then the numeric factorization, with a cancel check between
// (CHOLMOD cannot be interrupted inside either step). Minimum degree (AMD): the field is solved on
// the working mesh, and at its sizes AMD's fill is at most 19 % above nested dissection's (kitten;
// within 7 % on five other meshes) while its analysis is 5-7 times cheaper (analysis +
// factorization, METIS against AMD: kitten's 28 944 faces 0.15 / 0.09 s, 40 000 faces 0.17 /
// 0.08 s, 160 000 faces 0.91 / 0.38 s). CHOLMOD prints nothing.
void factorize(Solver& solver, const ComplexSparse& A, const Progress& progress) {
  pin_blas_kernels();
  solver.cholmod().print = 0;
  solver.cholmod().nmethods = 1;
  solver.cholmod().method[0].ordering = CHOLMOD_AMD;
  solver.analyzePattern(A);
  progress.check_cancel();
  solver.factorize(A);
  if (solver.info() != Eigen::Success)
    throw Error(ErrorCode::StageFailed,
                "cross field: sparse factorization failed (" + std::to_string(A.rows()) + " unknowns)");
}

// Power field with the constrained faces fixed: minimizes the energy over the free faces.
ComplexVector solve_constrained(const ComplexSparse& A, const std::vector<char>& fixed, const ComplexVector& z_fixed,
                                Progress& progress) {
  const int n = static_cast<int>(A.rows());
  std::vector<int> free_index(n, -1);
  int num_free = 0;
  for (int f = 0; f < n; ++f)
    if (!fixed[f]) free_index[f] = num_free++;
  ComplexVector z = z_fixed;
  if (num_free == 0) return z;
  std::vector<Eigen::Triplet<Complex>> triplets;
  ComplexVector rhs = ComplexVector::Zero(num_free);
  for (int col = 0; col < n; ++col)
    for (ComplexSparse::InnerIterator it(A, col); it; ++it) {
      const int row = static_cast<int>(it.row());
      if (fixed[row]) continue;
      if (fixed[col])
        rhs[free_index[row]] -= it.value() * z_fixed[col];
      else
        triplets.emplace_back(free_index[row], free_index[col], it.value());
    }
  ComplexSparse A_free(num_free, num_free);
  A_free.setFromTriplets(triplets.begin(), triplets.end());
  progress.update(0.3);
  Solver solver;
  factorize(solver, A_free, progress);
  progress.update(0.6);
  const ComplexVector z_free = solver.solve(rhs);
  for (int f = 0; f < n; ++f)
    if (!fixed[f]) z[f] = z_free[free_index[f]];
  return z;
}

// Smallest generalized eigenvector of A z = lambda M z (M = diag(area)) by inverse iteration.
ComplexVector smallest_eigenvector(const ComplexSparse& A, const std::vector<double>& area, Progress& progress) {
  const int n = static_cast<int>(A.rows());
  const Eigen::VectorXd mass = Eigen::Map<const Eigen::VectorXd>(area.data(), n);
  // A tiny shift keeps the factorization definite when a parallel field exists (lambda = 0).
  double trace_A = 0;
  for (int f = 0; f < n; ++f) trace_A += A.coeff(f, f).real();
  const double shift = 1e-8 * trace_A / mass.sum();
  ComplexSparse shifted = A;
  for (int f = 0; f < n; ++f) shifted.coeffRef(f, f) += shift * mass[f];
  progress.update(0.2);
  Solver solver;
  factorize(solver, shifted, progress);
  progress.update(0.4);

  std::mt19937 random(12345);
  std::uniform_real_distribution<double> uniform(-1, 1);
  ComplexVector x(n);
  for (int f = 0; f < n; ++f) x[f] = Complex(uniform(random), uniform(random));
  auto m_norm = [&](const ComplexVector& v) { return std::sqrt((v.cwiseAbs2().array() * mass.array()).sum()); };
  x /= m_norm(x);
  // Stop when successive iterates agree to ~0.01 rad (1 - |<y, x>_M| < 1e-4): the singularities
  // are settled by then (measured on the shared meshes; igea needs 17 iterations).
  constexpr int kMaxIterations = 60;
  constexpr double kEigenTolerance = 1e-4;
  for (int it = 0; it < kMaxIterations; ++it) {
    const ComplexVector mx = (x.array() * mass.array().cast<Complex>()).matrix();
    ComplexVector y = solver.solve(mx);
    y /= m_norm(y);
    // |<y, x>_M| -> 1 as the iterates align (up to a phase).
    const double overlap = std::abs((y.conjugate().array() * mass.array().cast<Complex>() * x.array()).sum());
    x = std::move(y);
    progress.update(0.4 + 0.5 * (it + 1) / kMaxIterations);
    if (1 - overlap < kEigenTolerance) break;
  }
  return x;
}

// Sectors around a vertex (fan: its outgoing halfedges, counter-clockwise) between consecutive
// feature/boundary edges a (outgoing, first) and b (incoming, last) map to
// n = (rho(a) + angles + residual rotations inside - rho(b)) / 90deg quarter turns, an exact
// integer. Counts those with n < 1 and one-face sectors with n != 1 (a triangle corner between
// two isolines must be 90deg): the parametrization has to collapse there.
int count_collapsed_sectors(const TriMesh& mesh, const std::vector<char>& feature_edge, const std::vector<int>& fan,
                            bool boundary, const std::vector<double>& eps, const std::vector<double>& rho) {
  const int k = static_cast<int>(fan.size());
  int start = -1;
  for (int j = 0; j < k && start < 0; ++j)
    if (is_feature_halfedge(mesh, feature_edge, fan[j])) start = j;
  if (start < 0) return 0;
  int collapsed = 0;
  const int end = boundary ? k : start + k;
  for (int j0 = start; j0 < end;) {
    int j1 = j0;
    double swept = rho[fan[j0 % k]] + corner_angle(mesh, fan[j0 % k]);
    while (!is_feature_halfedge(mesh, feature_edge, TriMesh::prev(fan[j1 % k]))) {
      swept += eps[TriMesh::prev(fan[j1 % k])];
      swept += corner_angle(mesh, fan[++j1 % k]);
    }
    swept -= rho[TriMesh::prev(fan[j1 % k])];
    const long n = std::lround(swept / kQuarter);
    if (n < 1 || (j1 == j0 && n != 1)) ++collapsed;
    j0 = j1 + 1;
  }
  return collapsed;
}

// Sectors around every vertex between consecutive feature/boundary halfedges: first (outgoing)
// halfedge, closing (incoming) halfedge, the incoming halfedges crossed inside, and quarter turns
// n = (rho(first) + angles + residual rotations inside - rho(last)) / 90deg (see
// count_collapsed_sectors).
struct Sector {
  int first = -1, last = -1;  // -1: the whole fan of an interior vertex without features
  std::vector<int> crossed;
  long turns = 0;
  // Feature sectors need one quarter turn (exactly one if one face wide). A whole fan needs three
  // (index <= +1): with none it cannot be mapped without folds, and one or two quarter turns
  // would squeeze every face around the vertex into 90 or 180 degrees.
  bool minimum_ok(long n) const { return first < 0 ? n >= 3 : crossed.empty() ? n == 1 : n >= 1; }
};
std::vector<Sector> feature_sectors(const TriMesh& mesh, const std::vector<char>& feature_edge,
                                    const std::vector<double>& eps, const std::vector<double>& rho) {
  std::vector<Sector> sectors;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const std::vector<int> fan = outgoing_halfedges(mesh, v);
    const int k = static_cast<int>(fan.size());
    int start = -1;
    for (int j = 0; j < k && start < 0; ++j)
      if (is_feature_halfedge(mesh, feature_edge, fan[j])) start = j;
    if (start < 0) {
      if (is_boundary_vertex(mesh, v)) continue;
      Sector s;
      double swept = 0;
      for (int h : fan) {
        s.crossed.push_back(TriMesh::prev(h));
        swept += corner_angle(mesh, h) + eps[s.crossed.back()];
      }
      s.turns = std::lround(swept / kQuarter);
      sectors.push_back(std::move(s));
      continue;
    }
    const int end = is_boundary_vertex(mesh, v) ? k : start + k;
    for (int j0 = start; j0 < end;) {
      Sector s;
      int j1 = j0;
      double swept = rho[fan[j0 % k]] + corner_angle(mesh, fan[j0 % k]);
      while (!is_feature_halfedge(mesh, feature_edge, TriMesh::prev(fan[j1 % k]))) {
        s.crossed.push_back(TriMesh::prev(fan[j1 % k]));
        swept += eps[s.crossed.back()];
        swept += corner_angle(mesh, fan[++j1 % k]);
      }
      s.first = fan[j0 % k];
      s.last = TriMesh::prev(fan[j1 % k]);
      s.turns = std::lround((swept - rho[s.last]) / kQuarter);
      sectors.push_back(std::move(s));
      j0 = j1 + 1;
    }
  }
  return sectors;
}

// Around an interior vertex, per spoke (the incoming halfedges `crossed`, in fan order): the angle
// around the vertex to the nearest spoke whose matching a move already changed (shift != 0); the
// whole angle sum where none has. The quarter turns a fan gives away go to spokes spread around it:
// at the centre of a fan-triangulated cap bounded by a circular feature every spoke is equally
// good, and the three chosen by the smallest residual alone fell side by side (cycloidal's pins
// with sharp edges: rim corners 30 and 75 degrees apart, and the cap's map folded).
std::vector<double> angles_from_moved_spokes(const TriMesh& mesh, const std::vector<int>& crossed,
                                             const std::vector<int>& shift) {
  const size_t k = crossed.size();
  std::vector<double> at(k, 0.0);
  double total = 0;
  for (size_t j = 0; j < k; ++j) {
    at[j] = total;
    total += corner_angle(mesh, TriMesh::next(crossed[j]));
  }
  std::vector<double> apart(k, total);
  for (size_t i = 0; i < k; ++i) {
    if (shift[crossed[i]] == 0) continue;
    for (size_t j = 0; j < k; ++j) {
      const double a = std::abs(at[j] - at[i]);
      apart[j] = std::min(apart[j], std::min(a, total - a));
    }
  }
  return apart;
}

// A sector must map to at least one quarter turn (exactly one when it is one face wide): with
// fewer, its two edges lie on one isoline through the vertex and the faces between them (often a
// whole strip between two feature curves) must fold. Nearest-axis choices miss this where the
// field is a compromise near 45deg to both edges (acute sectors, sliver faces, exact ties).
// Likewise an interior vertex needs index <= +1 (e.g. the centre of a fan-triangulated disc
// bounded by a circular feature gets the whole +4 of the disc). A missing quarter turn is moved
// into the sector from a neighbour, one per pass: across one of its inner edges (the edge's
// matching changes; its other end becomes a singularity, or its sector there gives up a quarter
// turn), or through one of its two bounding halfedges (that halfedge's own sector moves to its
// second nearest axis, within 90deg; the sector at the edge's other end gives up a quarter turn).
// Of the moves that keep the other sector at its minimum, the one with the smallest new residual
// / misalignment; around an interior vertex, the spoke farthest from those already moved first
// (angles_from_moved_spokes), the residual only between equals. Returns the number of moves. shift (3#F, antisymmetric)
// receives the matching changes of ordinary edges; eps, rho and edge_sector are updated.
int resolve_collapsed_sectors(const TriMesh& mesh, const std::vector<char>& feature_edge, std::vector<double>& eps,
                              std::vector<double>& rho, std::vector<int8_t>& edge_sector, std::vector<int>& shift) {
  constexpr double kSpreadTolerance = 1e-6;  // radians: spokes as far apart
  const int nh = mesh.num_halfedges();
  int resolved = 0;
  shift.assign(nh, 0);
  for (int pass = 0; pass < 16; ++pass) {
    const std::vector<Sector> sectors = feature_sectors(mesh, feature_edge, eps, rho);
    // Per halfedge: the sector it starts (at from(h)), closes (at to(h)) or is crossed in (at to(h)).
    std::vector<int> starts(nh, -1), closes(nh, -1), crossed_in(nh, -1);
    for (size_t i = 0; i < sectors.size(); ++i) {
      if (sectors[i].first >= 0) starts[sectors[i].first] = static_cast<int>(i);
      if (sectors[i].last >= 0) closes[sectors[i].last] = static_cast<int>(i);
      for (int h : sectors[i].crossed) crossed_in[h] = static_cast<int>(i);
    }
    std::vector<char> touched(nh, 0);
    bool changed = false;
    for (const Sector& s : sectors) {
      if (s.minimum_ok(s.turns)) continue;
      const long d = s.first >= 0 && s.crossed.empty() && s.turns > 1 ? -1 : 1;  // one quarter turn per pass
      // kind 0: rho(first) += d; kind 1: rho(last) -= d; kind 2: eps(crossed) += d (quarter turns).
      struct Move {
        int kind, h;
        double deviation;
        int other;
      };
      std::vector<Move> moves;
      if (s.first >= 0) {
        moves.push_back({0, s.first, rho[s.first] + d * kQuarter, closes[s.first]});
        moves.push_back({1, s.last, rho[s.last] - d * kQuarter, starts[s.last]});
      }
      for (int h : s.crossed) moves.push_back({2, h, eps[h] + d * kQuarter, crossed_in[mesh.opposite[h]]});
      const std::vector<double> apart =
          s.first < 0 ? angles_from_moved_spokes(mesh, s.crossed, shift) : std::vector<double>(moves.size(), 0.0);
      int best = -1;
      for (size_t i = 0; i < moves.size(); ++i) {
        const Move& m = moves[i];
        const int o = m.kind == 2 ? mesh.opposite[m.h] : m.h;
        if (touched[m.h] || touched[o]) continue;
        if (!(std::abs(m.deviation) < (m.kind == 2 ? M_PI : kQuarter))) continue;
        if (m.other >= 0 && !sectors[m.other].minimum_ok(sectors[m.other].turns - d)) continue;
        if (best < 0 || apart[i] > apart[best] + kSpreadTolerance ||
            (apart[i] > apart[best] - kSpreadTolerance && std::abs(m.deviation) < std::abs(moves[best].deviation)))
          best = static_cast<int>(i);
      }
      if (best < 0) continue;
      const Move& m = moves[best];
      if (m.kind == 2) {
        const int o = mesh.opposite[m.h];
        touched[m.h] = touched[o] = 1;
        eps[m.h] = m.deviation;
        eps[o] = -m.deviation;
        shift[m.h] -= static_cast<int>(d);  // eps = mismatch - q * 90deg
        shift[o] += static_cast<int>(d);
      } else {
        touched[m.h] = 1;
        rho[m.h] = m.deviation;
        edge_sector[m.h] = static_cast<int8_t>(mod4(edge_sector[m.h] + (m.kind == 0 ? -d : d)));
      }
      changed = true;
      ++resolved;
    }
    if (!changed) break;
  }
  return resolved;
}

// Constrained faces and the power field: fills field.num_overconstrained_faces and
// field.constrained_face, the constrained faces' angles theta (own frames) and their power field
// z_fixed. Returns the number of constrained faces.
int constrain_faces(const TriMesh& mesh, const FaceFrames& fr, CrossField& field, std::vector<double>& theta,
                    ComplexVector& z_fixed) {
  const int nf = mesh.num_faces();
  field.constrained_face.assign(nf, 0);
  int num_constrained = 0;
  for (int f = 0; f < nf; ++f) {
    int count = 0;
    for (int k = 0; k < 3; ++k) count += is_feature_halfedge(mesh, field.feature_edge, 3 * f + k);
    field.num_overconstrained_faces += count == 3;
  }
  for (int f = 0; f < nf; ++f) field.constrained_face[f] = face_constraint(mesh, fr, field.feature_edge, f, &theta[f]);
  constrain_acute_sectors(mesh, fr, field.feature_edge, field.constrained_face, theta);
  for (int f = 0; f < nf; ++f)
    if (field.constrained_face[f] != kFree) {
      z_fixed[f] = std::polar(1.0, 4 * theta[f]);
      ++num_constrained;
    }
  return num_constrained;
}

// Smoothest field on the free faces, solved in the proxy frames (constrained: one sparse system;
// unconstrained: smallest eigenvector), turned back onto the true faces into theta.
void solve_free_faces(const TriMesh& mesh, const FaceFrames& fr, const CrossField& field, int num_constrained,
                      ComplexVector& z_fixed, std::vector<double>& theta, Progress& progress) {
  const int nf = mesh.num_faces();
  const ProxyFrames proxy = proxy_frames(mesh, fr, field.feature_edge);
  for (int f = 0; f < nf; ++f)
    if (field.constrained_face[f])
      z_fixed[f] = std::polar(1.0, 4 * transfer_angle(theta[f], fr.e1[f], fr.e2[f], fr.normal[f], proxy.normal[f],
                                                      proxy.e1[f], proxy.e2[f]));
  progress.check_cancel();
  const ComplexSparse A = smoothness_matrix(mesh, fr, proxy);
  const ComplexVector z = num_constrained > 0 ? solve_constrained(A, field.constrained_face, z_fixed, progress)
                                              : smallest_eigenvector(A, fr.area, progress);
  for (int f = 0; f < nf; ++f)
    if (!field.constrained_face[f])
      theta[f] = transfer_angle(std::arg(z[f]) / 4, proxy.e1[f], proxy.e2[f], proxy.normal[f], fr.normal[f], fr.e1[f],
                                fr.e2[f]);
}

// Isoline sectors of feature/boundary halfedges, each from its own face (nearest axis), into
// field.edge_sector. Returns rho (3#F) = chart angle - sector * 90deg, in [-45deg, 45deg].
std::vector<double> assign_edge_sectors(const TriMesh& mesh, const FaceFrames& fr, const std::vector<double>& theta,
                                        CrossField& field) {
  const int nh = mesh.num_halfedges();
  field.edge_sector.assign(nh, -1);
  std::vector<double> rho(nh, 0.0);
  for (int h = 0; h < nh; ++h)
    if (is_feature_halfedge(mesh, field.feature_edge, h))
      field.edge_sector[h] =
          static_cast<int8_t>(mod4(nearest_quarter(wrap_angle(fr.angle[h] - theta[h / 3]), &rho[h])));
  return rho;
}

// Residual rotations across ordinary edges (they do not depend on the sectors); 0 elsewhere.
std::vector<double> ordinary_edge_residuals(const TriMesh& mesh, const FaceFrames& fr, const std::vector<double>& theta,
                                            const std::vector<char>& feature_edge) {
  std::vector<double> eps(mesh.num_halfedges(), 0.0);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0 || feature_edge[e]) continue;
    nearest_quarter(wrap_angle(theta[h / 3] - fr.angle[h] + fr.angle[o] + M_PI - theta[o / 3]), &eps[h]);
    eps[o] = -eps[h];
  }
  return eps;
}

// Matchings and the residual rotation eps[h] left after the quarter turns (the edge's chart
// angle on the far side minus its chart angle here minus matching * 90deg). Ordinary edges:
// nearest quarter turn, |eps| <= 45deg. Feature edges: the quarter turn that keeps both sides'
// own sectors, q(o) = q(h) + r + 2, so |eps| = |rho(o) - rho(h)| <= 90deg.
void compute_matchings(const TriMesh& mesh, const FaceFrames& fr, const std::vector<double>& theta,
                       const std::vector<int>& shift, CrossField& field, std::vector<double>& eps) {
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0) continue;
    const double mismatch = wrap_angle(theta[h / 3] - fr.angle[h] + fr.angle[o] + M_PI - theta[o / 3]);
    int q;
    if (field.feature_edge[e]) {
      q = field.edge_sector[o] - field.edge_sector[h] - 2;
      eps[h] = wrap_angle(mismatch - q * kQuarter);
    } else {
      q = nearest_quarter(mismatch, &eps[h]) + shift[h];
      eps[h] = mismatch - q * kQuarter;
    }
    eps[o] = -eps[h];
    field.matching[h] = static_cast<int8_t>(mod4(q));
    field.matching[o] = static_cast<int8_t>(mod4(-q));
  }
}

// Index = (angle defect - field rotation relative to parallel transport) / 90deg; on the
// boundary the defect is the turning pi - sum(angles), corrected by how far the two boundary
// edges are off their isolines. Every value is an integer up to rounding and they sum to 4 chi.
// Fills field.vertex_index, num_collapsed_sectors, index_sum, num_singularities and
// euler_characteristic; throws if the indices do not sum to 4 chi.
void compute_vertex_indices(const TriMesh& mesh, const std::vector<double>& eps, const std::vector<double>& rho,
                            CrossField& field) {
  const int nf = mesh.num_faces(), ne = mesh.num_edges(), nv = mesh.num_vertices();
  field.vertex_index.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    const std::vector<int> fan = outgoing_halfedges(mesh, v);
    const bool boundary = is_boundary_vertex(mesh, v);
    double turning = boundary ? M_PI : 2 * M_PI;
    for (size_t i = 0; i < fan.size(); ++i) {
      turning -= corner_angle(mesh, fan[i]);
      if (mesh.opposite[TriMesh::prev(fan[i])] >= 0) turning -= eps[TriMesh::prev(fan[i])];
    }
    if (boundary) turning += rho[TriMesh::prev(fan.back())] - rho[fan.front()];
    field.vertex_index[v] = static_cast<int>(std::lround(turning / kQuarter));
    field.num_collapsed_sectors += count_collapsed_sectors(mesh, field.feature_edge, fan, boundary, eps, rho);
  }
  for (int v = 0; v < nv; ++v) {
    field.index_sum += field.vertex_index[v];
    field.num_singularities += field.vertex_index[v] != 0;
  }
  field.euler_characteristic = nv - ne + nf;
  if (field.index_sum != 4 * field.euler_characteristic)
    throw Error(ErrorCode::StageFailed, "cross field: singularity indices sum to " + std::to_string(field.index_sum) +
                                            " quarter turns instead of 4 * " +
                                            std::to_string(field.euler_characteristic) + " (internal error)");
}

}  // namespace

std::vector<int> cone_quarter_turns(const TriMesh& mesh, const CrossField& field) {
  std::vector<int> cone(mesh.num_vertices(), 4);
  for (int h = 0; h < mesh.num_halfedges(); ++h)
    if (mesh.opposite[h] < 0) cone[mesh.from(h)] = cone[mesh.to(h)] = 2;
  for (int v = 0; v < mesh.num_vertices() && v < static_cast<int>(field.vertex_index.size()); ++v)
    cone[v] -= field.vertex_index[v];
  return cone;
}

Vec3 rotate_in_face(const TriMesh& mesh, int f, const Vec3& d, int k) {
  const Vec3 n = mesh.face_normal_unnormalized(f).normalized();
  const Vec3 d90 = n.cross(d);
  switch (mod4(k)) {
    case 0: return d;
    case 1: return d90;
    case 2: return -d;
    default: return -d90;
  }
}

double chart_angle(const TriMesh& mesh, int h, const Vec3& u_axis) {
  const Vec3 n = mesh.face_normal_unnormalized(h / 3).normalized();
  const Vec3 v = mesh.edge_vector(h);
  return std::atan2(v.dot(n.cross(u_axis)), v.dot(u_axis));
}

std::vector<char> detect_feature_edges(const TriMesh& mesh, const std::vector<char>& caller_features,
                                       double sharp_angle_deg) {
  const int ne = mesh.num_edges();
  std::vector<char> feature(ne, 0);
  const double sharp = sharp_angle_deg * M_PI / 180;
  for (int e = 0; e < ne; ++e) {
    const int h = mesh.edge_halfedge[e], o = mesh.opposite[h];
    if (o < 0) continue;
    if (!caller_features.empty() && caller_features[e]) feature[e] = 1;
    if (sharp_angle_deg >= 0) {
      const Vec3 a = mesh.face_normal_unnormalized(h / 3).normalized();
      const Vec3 b = mesh.face_normal_unnormalized(o / 3).normalized();
      if (std::atan2(a.cross(b).norm(), a.dot(b)) > sharp) feature[e] = 1;
    }
  }
  return feature;
}

CrossField compute_cross_field(const TriMesh& mesh, const CrossFieldOptions& options, Progress& progress) {
  const int nf = mesh.num_faces(), ne = mesh.num_edges(), nh = mesh.num_halfedges();
  if (nf == 0) throw Error(ErrorCode::InvalidMesh, "cross field: the mesh has no faces");
  if (!options.feature_edges.empty() && static_cast<int>(options.feature_edges.size()) != ne)
    throw Error(ErrorCode::InvalidArgument, "cross field: feature_edges has " +
                                                std::to_string(options.feature_edges.size()) +
                                                " entries, the mesh has " + std::to_string(ne) + " edges");
  CrossField field;
  const FaceFrames fr = compute_frames(mesh);

  field.feature_edge = detect_feature_edges(mesh, options.feature_edges, options.sharp_angle_deg);

  std::vector<double> theta(nf, 0.0);
  ComplexVector z_fixed = ComplexVector::Zero(nf);
  const int num_constrained = constrain_faces(mesh, fr, field, theta, z_fixed);
  progress.update(0.05);
  progress.check_cancel();
  if (num_constrained < nf) solve_free_faces(mesh, fr, field, num_constrained, z_fixed, theta, progress);
  progress.update(0.9);
  field.direction.resize(nf);
  for (int f = 0; f < nf; ++f) field.direction[f] = std::cos(theta[f]) * fr.e1[f] + std::sin(theta[f]) * fr.e2[f];

  std::vector<double> rho = assign_edge_sectors(mesh, fr, theta, field);

  // Residual rotations across ordinary edges, then the sectors that would collapse are repaired.
  field.matching.assign(nh, 0);
  std::vector<double> eps = ordinary_edge_residuals(mesh, fr, theta, field.feature_edge);
  std::vector<int> shift;
  field.num_resolved_sectors = resolve_collapsed_sectors(mesh, field.feature_edge, eps, rho, field.edge_sector, shift);

  compute_matchings(mesh, fr, theta, shift, field, eps);
  compute_vertex_indices(mesh, eps, rho, field);
  // Singularities no layout keeps apart or no seamless map follows: removed, then measured again.
  auto remeasure = [&]() {
    for (int f = 0; f < nf; ++f) field.direction[f] = std::cos(theta[f]) * fr.e1[f] + std::sin(theta[f]) * fr.e2[f];
    field.num_collapsed_sectors = field.index_sum = field.num_singularities = 0;
    compute_vertex_indices(mesh, eps, rho, field);
  };
  field.num_close_pairs = cross_field_detail::cancel_close_pairs(mesh, fr.area, options.cancel_pairs_within,
                                                                 options.keep_pairs_near, theta, eps, field);
  if (field.num_close_pairs > 0) remeasure();
  if (cross_field_detail::make_torus_field_admissible(mesh, fr.area, theta, eps, field)) remeasure();
  progress.update(1.0);
  return field;
}

}  // namespace qgp
