// Motorcycle graph simulation (internal to the tracer, paper §5.1 and §9).
//
// Separatrices ("motorcycles") start at time 0 from every corner vertex (singularity, feature or
// boundary corner, virtual corner, seed) and travel along exact parameter isolines, one triangle
// at a time, in the doubled fixed-point coordinates of each face's chart. Travel time = travelled
// parametric length, so it is chart independent and exact (a rational). Events are processed in
// time order; a motorcycle stops where it reaches a trail that was there earlier (T-junction),
// a corner vertex, a feature or the boundary ("walls", which exist from the start). Two
// motorcycles that reach one point at the same time cross (perpendicular) or both stop (head-on).
#pragma once
#include <functional>
#include <map>
#include <queue>
#include <string>
#include <vector>

#include "core/parametrization.h"
#include "core/progress.h"
#include "core/surface_point.h"
#include "tmesh/detail/vertex_star.h"
#include "tmesh/tmesh.h"

namespace qgp::tmesh_detail {

// Canonical identity of a point on the surface: a vertex, a point inside an edge (parameter
// lambda from the edge's first halfedge's origin, reduced), or a point inside a face (reduced
// rational chart coordinates).
struct PointKey {
  enum Type : int { Vertex = 0, Edge = 1, Face = 2 };
  int type = Vertex;
  int id = -1;
  Rational a, b;  // Edge: a = lambda; Face: (a, b) = (u, v); reduced
};
bool operator<(const PointKey& x, const PointKey& y);

struct RationalLess {
  bool operator()(const Rational& x, const Rational& y) const { return compare(x, y) < 0; }
};

struct NodeRecord {
  PointKey key;
  int frame_face = -1;  // chart of the node frame (vertex nodes: ring[0]'s face)
  SurfacePoint point;
};

// A piece of a motorcycle's path inside one face (pieces along an edge are kept in one face and
// registered for collisions in both).
struct Segment {
  int moto = -1;
  Rational t0, t1;  // travel times at start / end
  int face = -1;
  int dir = 0;              // travel direction in the face's chart
  P2 origin{};              // the motorcycle's source transported into this chart (on the line)
  int along_halfedge = -1;  // halfedge of `face` the piece runs along, or -1
  int start_vertex = -1, end_vertex = -1;
  int end_halfedge = -1;  // halfedge of `face` through whose edge it leaves, or -1
  bool dead = false;      // cut off by an earlier stop

  int64_t line() const { return origin[fixed_axis_of(dir)]; }
  // Moving coordinate at time t, and time at moving coordinate s.
  Rational coord_at(const Rational& t) const {
    return add_int(sense_of(dir) > 0 ? t : negate(t), origin[axis_of(dir)]);
  }
  Rational time_at(const Rational& s) const {
    const Rational d = add_int(s, -i128(origin[axis_of(dir)]));
    return sense_of(dir) > 0 ? d : negate(d);
  }
};

struct Motorcycle {
  int source_vertex = -1;
  int source_number = 0;      // direction number in the source's vertex frame
  std::vector<int> segments;  // in travel order
  bool stopped = false;
  Rational stop_time;
  std::map<Rational, int, RationalLess> junctions;  // travel time -> node on the trail
};

struct TraceStats {
  int motorcycles = 0;
  long long steps = 0;        // face-to-face advances
  int head_on = 0;            // motorcycles meeting head-on at one point and time
  int crossings = 0;          // perpendicular simultaneous crossings
  int vertex_passes = 0;      // passes through a mesh vertex
  int edge_runs = 0;          // pieces running exactly along a mesh edge
  int cut_crossings = 0;      // crossings of cut edges (transition applied)
  int cut_vertex_passes = 0;  // passes through a vertex whose one-ring is cut
  int virtual_corners = 0;    // closed walls without a corner got one
  int seeds = 0;
  int walls_not_isolines = 0;  // feature/boundary edges whose corners share neither u nor v
};

class MotorcycleTracer {
 public:
  // wall_edge: #E flags (features and boundary). max_steps: limit on face advances.
  MotorcycleTracer(const TriMesh& mesh, const ExactParametrization& param, std::vector<char> wall_edge,
                   long long max_steps, Progress& progress);
  void run();

  const TriMesh& mesh() const { return mesh_; }
  const std::vector<char>& wall_edge() const { return wall_edge_; }
  const std::vector<VertexStar>& stars() const { return stars_; }
  const std::vector<P2>& uv2() const { return uv2_; }
  const std::vector<NodeRecord>& nodes() const { return nodes_; }
  const std::vector<Segment>& segments() const { return segments_; }
  const std::vector<Motorcycle>& motorcycles() const { return motos_; }
  const TraceStats& stats() const { return stats_; }
  int fraction_bits() const { return fraction_bits_; }

  // Node at a canonical point (created on first use).
  int node_at(const PointKey& key);
  int vertex_node(int v);
  // The surface point (face chart coordinates in doubled units) of a point on a line.
  SurfacePoint surface_point(int face, const Rational& u, const Rational& v) const;
  // Position of a segment at time t as a surface point in the segment's face.
  SurfacePoint segment_point(const Segment& s, const Rational& t) const;
  // Key of the point with fixed coordinate c on axis `fixed` and moving coordinate s, in `face`.
  PointKey classify(int face, int fixed, int64_t c, const Rational& s) const;
  // Direction number at a node of a direction `dir` leaving it, given in `face`'s chart.
  int node_direction(int node, int face, int dir) const;

 private:
  struct FaceRecord {
    int segment;
    int dir;
    P2 origin;
  };
  struct Passage {
    int moto;
    Rational time;
    int ref_dir;  // travel direction in the vertex's ring[0] chart
  };
  struct PointRef {
    int vertex = -1;  // >= 0: the point is this vertex
    int face = -1, fixed = 0;
    int64_t c = 0;
    Rational s;
  };
  enum EventKind : int { Stop = 0, HeadOn = 1, Cross = 2, Exit = 3 };
  struct Event {
    Rational time;
    int kind = Exit;
    long long seq = 0;
    int a = -1, b = -1;  // Stop: a = later (stops), b = earlier; Meet: both; Exit: a = moto
    Rational ta, tb;     // times of a and b at the point
    int segment = -1;    // Exit: the segment that ends
    PointRef point;
  };
  struct EventAfter {
    bool operator()(const Event& x, const Event& y) const {
      const int c = compare(x.time, y.time);
      if (c != 0) return c > 0;
      if (x.kind != y.kind) return x.kind > y.kind;
      return x.seq > y.seq;
    }
  };

  [[noreturn]] void fail(const std::string& message) const;
  P2 transfer(int h, const P2& p) const;  // doubled coordinates across halfedge h
  Rational crossing(const P2& p, const P2& q, int fixed, int64_t c) const;
  bool blocking(int v) const;
  void prepare_walls_and_corners();
  void start_motorcycles();
  int new_segment(Segment s);
  void plan_in_corner(int m, int v, int corner, int dir, const P2& origin_in_corner_face, const Rational& t0);
  void plan_from_vertex(int m, int v, int face, int dir, const P2& origin, const Rational& t0);
  void plan_from_edge(int m, const Segment& prev);
  void check_faces(int segment_id, const FaceRecord& rec, int face);
  void check_vertex(int v, const Passage& p);
  void push(Event e);
  void process(const Event& e);
  void stop(int m, const Rational& t, int node);
  bool add_junction(int m, const Rational& t, int node);  // true if new
  int node_for(const PointRef& p);
  bool alive_at(int m, const Rational& t) const { return !motos_[m].stopped || compare(motos_[m].stop_time, t) >= 0; }

  const TriMesh& mesh_;
  const ExactParametrization& param_;
  std::vector<char> wall_edge_;
  long long max_steps_;
  Progress& progress_;
  int fraction_bits_ = 0;
  std::vector<P2> uv2_;           // 3#F doubled corner coordinates
  std::vector<P2> translation2_;  // 3#F doubled translations
  std::vector<char> face_ok_;     // positive parametric orientation
  std::vector<VertexStar> stars_;
  std::vector<Segment> segments_;
  std::vector<Motorcycle> motos_;
  std::vector<std::vector<FaceRecord>> face_records_;
  std::map<int, std::vector<Passage>> passages_;
  std::vector<NodeRecord> nodes_;
  std::map<PointKey, int> node_index_;
  std::priority_queue<Event, std::vector<Event>, EventAfter> queue_;
  long long seq_ = 0;
  int finished_ = 0;
  TraceStats stats_;
};

}  // namespace qgp::tmesh_detail
