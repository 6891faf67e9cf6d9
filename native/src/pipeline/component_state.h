// One connected component on its way through the pipeline: the component itself and every stage's
// result, each stored with the key of the inputs it was computed from (pipeline/stage_result.h).
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "core/error.h"
#include "core/mesh.h"
#include "core/parametrization.h"
#include "cross_field/cross_field.h"
#include "cut_graph/cut_graph.h"
#include "igm/cell_map.h"
#include "igm/integer_grid_map.h"
#include "pipeline/stage_result.h"
#include "quad_extraction/layout_quads.h"
#include "quad_extraction/quad_extraction.h"
#include "quad_extraction/untangle_quads.h"
#include "quantization/quantization.h"
#include "quantization/round_quantization.h"
#include "seamless_map/seamless_map.h"
#include "tmesh/tmesh.h"

namespace qgp {

// Stage 2: the seamless map made exact (features and boundary on exact isolines) and its T-mesh.
struct TracedMap {
  std::vector<char> isoline_edges;  // #E: feature and boundary edges kept as isolines
  ExactParametrization exact;       // the seamless map, exact
  TMesh tmesh;
};

// Stage 3: integer T-edge lengths.
struct Quantized {
  QuantizationResult result;
  int fold_rounds = 0;          // re-quantizations that kept folding zero edges at 1 (greedy)
  int kept_positive_edges = 0;  // T-edges kept at length >= 1 by them (and by the flip rounds)
  // Re-quantizations that kept zero edges beside flipped layout quads at 1 (greedy), and the layout
  // quads flipped against the surface before and after them (-1: the layout is not a valid mesh).
  int flip_rounds = 0;
  int flipped_layout_quads_before = 0, flipped_layout_quads = 0;
  int64_t quads_before_flip_rounds = 0;  // the quantization's quads before them
  double flip_seconds = 0;               // the layouts placed, untangled and judged, and the re-quantizations
  // The quad count asked of this component (0: none, an edge length was asked), the scale the
  // density gave, the re-quantizations that moved the scale toward the count, and the fewest
  // quads the layout allows when they are more than asked (-1: not measured).
  double target_quads = 0;
  double nominal_scale = 0;
  int count_rounds = 0;
  int64_t fewest_quads = -1;
  // When the count jumps over the target between two nearby scales: the counts on either side.
  std::optional<std::array<int64_t, 2>> count_step;
  // The round baseline's rounded map: it is the integer-grid map of that quantization.
  std::optional<RoundedMap> rounded;
  // The layout's quads of `result`, placed on the surface and untangled as quad extraction places
  // them (greedy, where they form a valid mesh: the flip rounds judged them), so that extraction
  // does not place them again.
  struct PlacedLayout {
    LayoutQuads layout;
    UntangleStats untangle;
  };
  std::optional<PlacedLayout> placed_layout;
};

// Stage 4: the integer-grid map (1 unit = 1 quad).
struct IgmResult {
  ExactParametrization map;
  IgmStats stats;
  bool escalated = false;  // every attempt the policy has for grid UVs ran (or none applies)
};

// The fallback map on the mesh with the T-mesh inserted (paper §7.1.1), where the global solve's
// map stays flipped or wound.
struct CellMapFallback {
  bool ran = false;            // false: the integer-grid map did not need it
  bool used = false;           // it has no flipped triangle and no wound one-ring: the run's uv map
  std::string failure;         // why it could not be built (empty otherwise)
  std::optional<CellMap> map;  // when used
  CellMapStats stats;
};

// Where a component's quads come from.
enum class QuadSource {
  IntegerGridMap,  // extracted from the integer-grid map (QEx)
  TMeshLayout,     // each quantized T-mesh cell as its w x h grid (quad_extraction/layout_quads)
  SplitTriangles,  // the part's triangles (decimated to the budget) split into 3 quads each
};
const char* quad_source_name(QuadSource source);

// Stage 5: the component's quads, and why they come from where they do.
struct QuadChoice {
  QuadExtraction extraction;
  QuadSource source = QuadSource::IntegerGridMap;
  std::string why_not_map;  // for TMeshLayout: why the integer-grid map's quads were not taken
  LayoutQuadsStats layout;  // for TMeshLayout
  UntangleStats untangle;   // flipped quads unfolded after extraction
};

// Why a component of a many-part mesh could not be quadded in the last run: it is kept as its
// triangles, and every other component is still quadded.
struct PartFailure {
  std::string stage;  // the stage that failed (a progress stage name, e.g. "tmesh")
  ErrorCode code = ErrorCode::StageFailed;
  std::string message;
};

struct FieldKey {
  double edge_length = 0;    // target quad edge length its close singularity pairs were judged at
  bool cancel_pairs = true;  // false: the field without cancelled pairs (policy.h)
};

struct SeamlessKey {
  uint64_t cut = 0;
  double edge_length = 0;  // target quad edge length the map was solved for (1 uv unit)
  uint64_t sizing = 0;     // sizes_hash of the sizing field (0: uniform)
  bool operator==(const SeamlessKey& o) const {
    return cut == o.cut && edge_length == o.edge_length && sizing == o.sizing;
  }
};
struct QuantizationKey {
  uint64_t traced = 0;
  double scale = 0;         // quads per seamless uv unit, as the density gives it
  double target_quads = 0;  // the component's share of the quad count asked (0: an edge length)
  Quantizer quantizer = Quantizer::Greedy;
  bool operator==(const QuantizationKey& o) const {
    return traced == o.traced && scale == o.scale && target_quads == o.target_quads && quantizer == o.quantizer;
  }
};

struct ComponentState {
  // The component, fixed once prepared (a new one is prepared when features or the working
  // resolution change).
  TriMesh mesh;                     // the component as its own mesh (or its working mesh)
  std::vector<int> vertex_map;      // component vertex -> intake mesh vertex
  std::vector<int> face_map;        // component face -> intake mesh face (-1 on a working mesh)
  std::vector<char> feature_edges;  // #E of `mesh`: caller's and dihedral-angle feature edges
  std::vector<char> tip_vertices;   // #V of `mesh`: sharp tips (sharp_tip_vertices), where layout points stay
  int euler_characteristic = 0;     // of the intake component
  // A dense component of a remesh job is decimated to a working resolution for the target, and a
  // needle-covered one with features that failed on its own triangles is remeshed isotropically
  // (intake/working_mesh.h); the quads are projected back onto the component itself, kept here.
  std::optional<TriMesh> full_mesh;
  bool remeshed = false;                 // full_mesh was remeshed, not decimated
  std::vector<int> full_face_map;        // full_mesh face -> intake mesh face
  std::vector<char> full_feature_edges;  // #E of full_mesh
  int working_face_budget = 0;           // the face budget `mesh` was made for (0: no limit)

  // Stage results; each key names what it was computed from.
  StageResult<CrossField, FieldKey> field;
  StageResult<CutGraph, uint64_t> cut;             // field
  StageResult<SeamlessMap, SeamlessKey> seamless;  // cut, edge length
  StageResult<TracedMap, uint64_t> traced;         // seamless
  StageResult<Quantized, QuantizationKey> quantization;
  StageResult<IgmResult, uint64_t> igm;             // quantization
  StageResult<CellMapFallback, uint64_t> cell_map;  // igm
  StageResult<QuadChoice, uint64_t> quads;          // igm
  // Set when a stage failed on this component in the last run; later stages skip it.
  std::optional<PartFailure> failure;
  // A failed component of a remesh job (failure says why) rescued by policy.h's failed-part ladder:
  // quadded at this fraction of the quad edge length asked (quads holds them), or else by splitting
  // its triangles; or first, at the density asked, with the field without cancelled close pairs.
  double finer_edge_factor = 1;
  std::optional<QuadChoice> split_quads;
  bool without_cancelled_pairs = false;
  bool rescued_on_remesh = false;  // quadded on an isotropic remesh (remeshed) after failing on its own
  // Whether the component has quads in the last run: its own, or those of a rescue.
  bool quadded() const {
    return !failure || finer_edge_factor < 1 || split_quads.has_value() || without_cancelled_pairs || rescued_on_remesh;
  }
  // The quads in use with their folds collapsed, where collapse_folds collapsed any (policy.h).
  std::optional<QuadChoice> collapsed_quads;
  const QuadChoice& quad_choice() const {
    return collapsed_quads ? *collapsed_quads : split_quads ? *split_quads : *quads;
  }

  // Model units per uv unit of the seamless map.
  double seamless_edge_length() const { return seamless.key().edge_length; }
  // The stored seamless map / integer-grid map was computed from the stored results before it
  // (not so after a run that failed on the way).
  bool seamless_is_current() const {
    return seamless.has_value() && seamless.key().cut == cut.id() && cut.computed_from(field.id());
  }
  bool igm_is_current() const {
    return igm.computed_from(quantization.id()) && quantization.has_value() &&
           quantization.key().traced == traced.id() && traced.computed_from(seamless.id()) && seamless_is_current();
  }
};

}  // namespace qgp
