// The pipeline's decisions. Every fallback that keeps the output valid is a ladder here, one
// function each, read top to bottom; each result says which rung it ended on. The stages under
// native/src compute; only this file chooses between their results.
//
//   quantization   quantize_to_count        the density's scale; moved toward the quad count asked
//                                           when its count is off; the fewest quads measured when
//                                           more than asked remain
//                  quantize_without_folds   greedy quantization; zero T-edges whose collapse folds
//                                           the quad layout kept at length 1, pinched cells there
//                                           kept 2 quads across, quantized again; then
//                                           those around layout quads that stay flipped against
//                                           the surface, while fewer stay flipped
//   integer-grid   solve_integer_grid_map   default solve (for quads, its repair cut short where it
//   map                                     stalls or where the untangle finishes it, and none where
//                                           the integer values make triangles degenerate); for
//                                           grid UVs, while the map is
//                                           irregular and the map untangle alone does not make it
//                                           regular: the re-linearized penalty phase, then the
//                                           all-faces solve (on parts up to kMaxAllFacesTriangles),
//                                           each stopped where its repair stagnates; then the map
//                                           untangle (for quads, only where few triangles are left)
//   uv map         fallback_cell_map        where the map stays flipped or wound: the §7.1.1 cell
//                                           map, used when it is flip-free and unwound
//   quads          choose_quads             the map's quads when the map is regular and they form a
//                                           valid mesh; else (or when fewer stay flipped) the
//                                           T-mesh layout's quads; else a refusal naming why
//   cross field    field_serves             the field with close +1/-1 pairs cancelled (its seamless
//                                           map's repair cut short); where that map folds, the field
//                                           with the pairs near its folds kept (when any is,
//                                           keep_pairs_near_folds); the field without, where the
//                                           seamless map still folds
//   failed part    retry_on_isotropic_remesh   a remesh part with feature edges across needle
//                                           triangles (a CAD tessellation) that failed on its own
//                                           triangles (or whose seamless map started folded there,
//                                           remesh_follows_a_folded_start): run again on an
//                                           isotropic remesh of them;
//                  kMaxQuadDistanceInEdges  also one whose quads lie far off its surface
//                  retry_without_cancelled_pairs   a remesh part that failed after its field
//                                           cancelled close pairs: run again with the field without
//                  quads_of_split_triangles a remesh part a stage failed on (StageFailed): its triangles,
//                                           decimated to its quad budget, split into 3 quads each
//                                           (decimated less, kSplitFacesGrowth times at a time,
//                                           while quads are flipped)...
//                  kFinerEdgeFactors        ...unless its quantized layout gave no valid quads (a hole
//                                           or handle narrower than a quad) and the part alone at 1/2,
//                                           else 1/4 of the quad edge length gives no more quads
//                                           (while quads stay flipped at 1/2, the one of the two
//                                           that leaves fewest)
//   flipped part   kFinerFlipShare          a minor part whose quads stay flipped against the
//                                           surface: alone at the finer density where fewest stay
//                                           so, when fewer than its own
//                  kFlipRescueShare         a small part whose quads stay flipped against the
//                                           surface (also after the finer density): its split
//                                           triangles, when they have none
//                  collapse_folds           any part whose quads still stay flipped, or has slivers
//                                           (or quads with a collapsed edge): those untangled, then
//                                           collapsed, while fewer stay so
//   collapsed edge kFinerFlipShare          a minor part whose quads keep a collapsed edge after
//                                           that (its fewest quads fold onto each other): alone at
//                                           the finer density where fewest stay flipped, then
//                                           collapsed, when fewer than its own
#pragma once
#include <limits>

#include "core/progress.h"
#include "pipeline/component_state.h"
#include "pipeline/options.h"

namespace qgp {

// A new remesh density keeps a decimated working mesh until it needs a budget more than this many
// times the one the mesh was made for...
constexpr int kMaxWorkingBudgetGrowth = 4;
// ...and the seamless map until the target edge length is more than this many times shorter or
// longer than the one the map was solved for (rescaled further, the solver's tolerances no longer
// match the grid and results drift from a fresh run's).
constexpr double kMaxSeamlessRescale = 2;
// The seamless map's local repair pass ends after this many rounds over regions of at least half
// the part without fewer bad triangles; the global solve in the field's frame and a second local
// pass follow. mnf07 with sharp edges at 60 degrees, 2 000 quads: rounds 0-7 brought its bad
// triangles 92 -> 5, rounds 8-23 stayed at 5-8 over 21 492 of its 22 340 triangles (3-8 s a round),
// and the global solve then removed them. It was one turn of the four strategies (4) while that
// solve cost 15-45 s; with the slacks eliminated (stop 49) it costs about 7 s, and two wide rounds
// at about 2 s each were the bound (mnf07: 21.0 -> 16.2 s, the same quads). The second wide round
// then left the count as it was (mnf07 and fandisk at 60 degrees: 5 and 2 bad triangles), and the
// sweep tests pass with one (stop 50: mnf07 at 2 000 quads 14.3 -> 11.8 s, fandisk 3.3 -> 2.8 s,
// the same quads). Rounds over small regions go on (ogre's part 43: a single bad triangle for 7
// rounds, then none; under 1 s a round).
constexpr int kSeamlessStagnantRounds = 1;
// The cross field cancels pairs of singularities of index +1 and -1 (off features, at most 2 edges
// apart) joined by a path of edges shorter than this share of the quad edge length: the layout
// cannot keep them apart without a whole quad between them (a scan's noise makes many:
// dragon-genus1's 20 000-triangle working mesh has 481 singularities, 312 of them next to one of
// the other sign).
constexpr double kCancelPairsWithin = 1.0;
// A field made for one edge length serves another as the seamless map does (seamless_map_serves);
// the field without cancelled pairs, the fallback below, serves a request with or without them.
bool field_serves(const FieldKey& stored, double edge_length, bool cancel_pairs);
// A field whose cancelled pairs leave its seamless map folded (flipped or degenerate triangles,
// wound one-rings: the curvature they held has nowhere to go) gives way first to the field with the
// pairs near the folds kept (component_stages.h: keep_pairs_near_folds; dragon-genus1 at 500 quads:
// 1 flipped triangle and 1 wound one-ring after 14 short repair rounds with 125 pairs cancelled;
// regular with 115 cancelled and 11 kept, 251 singular points instead of 481), then, where its map
// still folds or no pair is near the folds, to the field without cancelled pairs (ogre and
// dragon-genus1 at 8 000 quads: a fold more than 8 rings from every cancelled pair).
bool seamless_map_folds_where_pairs_were_cancelled(const ComponentState& state);
// That first map, with pairs cancelled, gets a short repair: it stops after this many rounds
// without fewer bad triangles and skips the escalations (the rounds that move shared coordinates,
// the global solve in the field's frame), as the field without cancelled pairs follows
// (dragon-genus1: its map with pairs cancelled stayed at one bad triangle for 19 of 24 rounds at
// 500 quads, and the global solve took 22 s of its 29 s; at 8 000 quads 50 s of 81 s; both then
// fell back).
constexpr int kCancelledPairsStagnantRounds = 8;
void bound_repair_where_pairs_were_cancelled(const ComponentState& state, SeamlessMapOptions& options);
// A remesh part that failed at quantization, the integer-grid map or quad extraction with a field
// whose close pairs were cancelled is first run again, at the density asked, with the field
// without cancelled pairs, before the rescues below (dragon-genus1 at 2 000 quads: 123 pairs
// cancelled, its extracted quads had 2 non-manifold edges, and the split-triangle rescue made
// 8 004 quads with 3 876 irregular vertices).
bool retry_without_cancelled_pairs(const ComponentState& state);
// A remesh part quadded on its own needle triangles (as below: features, needles over
// kRemeshAboveNeedleShare) or coarse ones (features, triangles over kCoarseEdgeInQuads quad edges
// long over that share: intake/working_mesh.h) whose quads lie farther than this many target quad
// edges from its surface, either way, is also run again on an isotropic remesh, and takes those
// quads when they lie closer: a map on needles can be regular and still cut across the part (a
// CAD-style cylinder of needle fans at 2 000 quads: 8.6 % of the diagonal, 3 quad edges, on its
// own triangles; 0.12 % on a remesh); on a few coarse triangles it may lay a curved rim on one
// straight isoline (block with edges over 40 degrees did, 1.21 % of the diagonal off at 8 000 quads,
// until the quarter turns of its fan's centre were spread around the disc: cross_field.cpp,
// angles_from_moved_spokes; 0.14 % on its own triangles now).
constexpr double kMaxQuadDistanceInEdges = 0.5;
bool remesh_may_bring_quads_closer(const ComponentState& state, Job job, double edge_length);
// A remesh part that failed on its own triangles, which has feature edges and needles over
// kRemeshAboveNeedleShare of its area (intake/working_mesh.h), is first run again on an isotropic
// remesh of itself, before every other rescue. Not before it fails: parts whose map holds on their
// needles keep their own triangles, which are faster and give fewer irregular vertices (joint with
// edges over 60 degrees at 2 000 quads: 0.22 s and 11 irregular vertices on its 446 triangles, 1.7 s
// and 24 on the remesh); featuretype's map folds on them (15 flipped triangles).
bool retry_on_isotropic_remesh(const ComponentState& state, Job job);
// Such a part goes there at once, without a repair on its needles, when its seamless map starts
// with more than this share of its triangles flipped or degenerate (the stage fails, the isotropic
// remesh follows): featuretype with edges over 40 degrees at 2 000 quads started with 126 of its
// 3 476 triangles (3.6 %) flipped, 14 repair rounds and a global solve (12 s, three rounds finished
// by Ipopt) left 15 and its T-mesh failed; joint, whose map holds on its needles, starts with none.
constexpr double kMaxBadShareToRepairOnNeedles = 0.01;
// True when the part's seamless map is solved that way (a remesh job that rescues failed parts).
bool remesh_follows_a_folded_start(const ComponentState& state, Job job, bool rescues_failed_parts);

// Re-quantizations against a folding layout.
constexpr int kMaxFoldRounds = 8;
// Re-quantizations against layout quads flipped against the surface, and how many cells away from
// theirs zero edges are kept at most (see quantize_without_folds).
constexpr int kMaxFlipRounds = 4;
constexpr int kMaxFlipRings = 3;
// No flip round is tried when more than this share of the layout's quads stay flipped (cycloidal's
// small gear parts: 30 of 115, 47 of 263; the rounds cost seconds there and left them flipped).
constexpr double kMaxFlipShare = 0.05;
// A flip round is kept only while its quantization has at most this many times the quads of the one
// before the flip rounds: each zero edge kept at 1 adds a row of quads, and the final quads are
// untangled and collapsed anyway (dragon-genus1 at 500 quads: the round that left 12 of 24 layout
// quads flipped kept 583 edges at 1 and gave 3 263 quads for the 1 219 the layout allows at least).
constexpr double kMaxFlipRoundGrowth = 1.25;
// Symmetry, relative to the bounding-box diagonal: input vertices this close to a plane are moved
// onto it before the cut (no sliver beside them), and the half's quad boundary vertices this close
// are welded to their mirror image (extraction puts them on the plane; projection onto a decimated
// mesh's original may move them off by rounding).
constexpr double kSymmetrySnapTolerance = 1e-5;
constexpr double kSymmetryWeldTolerance = 1e-4;

// True when a seamless map solved for `solved_for` serves a run at `edge_length` (rescaled).
bool seamless_map_serves(double solved_for, double edge_length);

// Sharp tips: inner vertices whose triangles' angles sum to less than kMaxTipAngleSum. The field
// puts a singularity on such a tip, but where the T-mesh layout's quads are used, a collapsed cell
// merged the tip's node with its neighbours and their average cut the tip off: cow's horn tips
// (101 degrees) lay 1.6 % of the diagonal from the nearest quad vertex at 8 000 quads. Points merged
// with a tip's node now lie on the tip (extract_layout_quads' pinned vertices). Of the 27 shared
// meshes, cow (3 tips), truck (1) and dragon-genus1 (34) have such vertices in their input.
constexpr double kMaxTipAngleSum = M_PI;
std::vector<char> sharp_tip_vertices(const TriMesh& mesh);

// The component's greedy quantization, from `first`, the T-mesh quantized at a scale without
// bounds (the count search's closest trial, not quantized again). A valid quantization can still
// collapse cells so that the layout folds (a regular point between two quads only, two quads on
// both sides of one edge): the zero edges there, and in a widening ring of cells around, are kept
// at length 1, a pinched cell there whose single quad repeats a node is kept 2 quads across
// (keep_pinched_cell_open; dragon-genus1's cluster of three singular points at 2 000 quads), and
// the T-mesh is quantized again, up to kMaxFoldRounds times. Then, while the
// layout's quads placed on the surface stay flipped against it (collapsed cells squeeze them where
// the part is thin or sharply curved), the zero edges around their cells are kept at 1 the same
// way, up to kMaxFlipRounds times and kMaxFlipRings cells away; a round is kept only when it leaves
// fewer flipped quads in a valid layout, with at most kMaxFlipRoundGrowth times the quads; the
// round one ring wider, which follows each round not kept, runs beside it on a second thread and is
// cancelled when the round is kept (core/run_ahead.h: the same rounds and quads with one thread).
// The quads keep their size where that needs no collapse.
Quantized quantize_without_folds(const ComponentState& state, QuantizationResult first, Progress& progress);

// Re-quantizations that move the scale toward a component's share of the quad count asked...
constexpr int kMaxCountRounds = 8;
// ...until its count is within this share of the target (twice it is the +-5 % promised).
constexpr double kCountTolerance = 0.025;

// The component's greedy quantization for `target_quads` quads (0: no count asked, an edge length
// was): first at the density's `scale` (its ideal quads are the surface area over the edge length
// squared, but the T-mesh layout rounds short arcs up, most at coarse densities), kept when its
// count is within twice kCountTolerance of the target (the promise: +-5 %). Otherwise, while the
// count is more than kCountTolerance off the target, the scale moves by sqrt(target / count), or to the
// middle of the bracket of scales that gave fewer and more quads when that step leaves it, up to
// kMaxCountRounds times. When the closest count is still more than twice kCountTolerance above the
// target, the fewest quads the layout allows are measured (a quantization at a vanishing scale keeps
// only the lengths validity needs) into fewest_quads; when they are fewer than the target, the
// search goes on up to kMaxCountRounds more times inside the bracket. The closest count's scale
// (never the vanishing one, whose quads ignore the surface's proportions) is quantized by
// quantize_without_folds.
Quantized quantize_to_count(const ComponentState& state, double scale, double target_quads, Progress& progress);

// Quads have a fallback (the T-mesh layout), grid UVs do not: only grid-UV jobs pay for the
// integer-grid map's escalating attempts...
bool escalates_integer_grid_map(Job job);
// ...and a larger budget of its repair rounds (kEscalatedStagnantRounds). Without escalation the map's repair stops
// after kRepairRoundsWithoutEscalation rounds (three turns of the four repair strategies), or after
// kStagnantRoundsWithoutEscalation rounds (one turn) without fewer bad triangles: on 18 shared
// meshes, maps that became regular took at most 9 Ipopt solves in all, while maps that stayed
// flipped (their quads then come from the layout) spent up to 24 rounds, most over their whole
// mesh: minutes on dragon and cycloidal. It also stops once the bad triangles have not halved over
// kHalvingRoundsWithoutEscalation rounds: at 2 000 quads on the 27 shared meshes (2026-11-28), the
// maps that became regular halved them every 4 rounds or faster (fertility: 17 17 17 17 1 0), while
// those that stayed flipped crept down to a plateau (dragon-genus1: 600 341 66 59 55 54 54 ...,
// 5-9 s a round; cycloidal's largest part: 229 131 95 91 76 76 74 78 68 66 66 66).
// Nor is it repaired at all (nor untangled) where the integer values alone make triangles
// degenerate, as a quantization that collapses a sliver between two T-edges does: no such map is
// regular (stanford-bunny at 1 000 quads: 3 such triangles, 9 repair rounds and 3.4 s for nothing).
constexpr int kRepairRoundsWithoutEscalation = 12;
// ...and it is untangled only where at most this share of its triangles are flipped or degenerate:
// on the shared meshes at 2 000 and 8 000 quads (2026-12-05), the untangle made the map regular
// where up to 0.14 % were (mnf07 without sharp edges at 2 000: 32 of 22 340), and never where 3.4 %
// or more were (fandisk with sharp edges at 60 degrees: 440 of 12 946; block: 1 410 of 5 380, 5.5 s
// for 1 215 left).
// The untangle also ends the repair early: at the first round of each plateau of the bad triangles
// (a round that leaves them no fewer), when at most this share are flipped or degenerate, the pose
// is rounded and untangled as a trial, and the repair stops there when that makes the map regular
// (stanford-bunny at 8 000 quads: 16 4 4 3 3 bad, then 2 1 1 1 1 1 over six more rounds whose
// regions kept growing, 4.4 s, before the untangle made it regular; now it stops at the second 3,
// and the run takes 4.8 s instead of 8.9). A trial that fails costs up to 0.3 s (armadillo, mnf07).
constexpr double kMaxShareToUntangle = 0.01;
// A trial counts only where the untangle moves at most this many vertices per flipped or degenerate
// triangle: the moved vertices bend the quads around them. On the shared meshes at 2 000 and 8 000
// quads the trials that made maps regular moved 2 per triangle (stanford-bunny 6 for 3; spot,
// nefertiti, fertility, face, rocker-arm), except camelhead (8 and 22 for 1: at 8 000 quads its
// Hausdorff distance went 0.85 -> 1.01 %, over the 1 % bound; its repair reaches a map the usual
// untangle fixes with 2) and mnf07 at 8 000 with sharp edges (53 for 3).
constexpr int kMaxUntangleMovesToFinish = 3;
constexpr int kStagnantRoundsWithoutEscalation = 4;
constexpr int kHalvingRoundsWithoutEscalation = 4;
// The escalated attempts (grid UVs) stop their repair after this many rounds without fewer bad
// triangles (two turns of the strategies); they used to run all 24. joint at 300 quads: the same
// map (1 flipped triangle, 1 wound one-ring left), 36 s before, 14 s after.
constexpr int kEscalatedStagnantRounds = 8;
// The all-faces attempt runs on parts of at most this many triangles: each of its repair rounds is
// an Ipopt solve with every triangle under constraints. igea (268 686 triangles, 2 000 quads): one
// round took over 3 minutes, and the grid-UV job ran past 25 minutes there; face.obj (51 712):
// about 6 s a round.
constexpr int kMaxAllFacesTriangles = 100000;
// True when a stored map serves a job that does (escalate) or does not escalate.
bool integer_grid_map_serves(const IgmResult& map, bool escalate);

// The component's integer-grid map: the default attempt (its repair bounded as above unless
// `escalate`); when `escalate` and the map has flipped or degenerate triangles or wound one-rings,
// the map untangle, kept when it leaves none; else the re-linearized penalty attempt (kept only if
// it has fewer), the untangle again, else the all-faces attempt (kept only if it has fewer).
// Finally the map untangle moves vertices where flipped or degenerate triangles remain. stats.path
// tells the rungs taken.
IgmResult solve_integer_grid_map(const ComponentState& state, bool escalate, Progress& progress);

// The round baseline's rounded map as the integer-grid map (no attempt applies).
IgmResult rounded_integer_grid_map(const RoundedMap& rounded);

// Flipped and degenerate triangles and wound one-rings of an integer-grid map.
int irregular_elements(const IgmStats& stats);

// Where the integer-grid map keeps flipped triangles or wound one-rings: the §7.1.1 cell map,
// used when it has neither (degenerate triangles alone do not call for it: its collapsed cells
// have many more). A cell map that cannot be built is reported, not thrown.
CellMapFallback fallback_cell_map(const ComponentState& state, Progress& progress);

// The map a grid-UV output of the component uses: the cell map where one was built and used for
// the current integer-grid map; null: the integer-grid map itself.
const CellMap* cell_map_in_use(const ComponentState& state);

// The component's quads: those of the integer-grid map when it is regular and they form a
// consistently oriented 2-manifold of the component's Euler characteristic; otherwise, or when
// some stay flipped after the untangle, those of the quantized T-mesh layout (kept if valid and
// fewer stay flipped). Throws Error(StageFailed) naming why when neither is valid.
QuadChoice choose_quads(const ComponentState& state, Progress& progress);

// A remesh part whose quads failed at one of these stages (its T-mesh exists, the quantization
// collapsed it) is run again alone at these fractions of the quad edge length, in order.
constexpr double kFinerEdgeFactors[] = {0.5, 0.25};
bool finer_density_may_help(const std::string& failed_stage);

// A part whose chosen quads stay flipped against the surface and that makes at most this share of
// all quads is quadded alone at the finer densities of kFinerEdgeFactors in turn, until one leaves
// none flipped, and takes the quads of the one that leaves fewest, if fewer than its own (ogre's
// part 42 at 2 000 quads, genus 1: 8 of its 316 stay flipped; three small parts of cycloidal at 500
// quads with edges over 40 degrees: 9 of 24 at half the edge length, none of 80 at a quarter)...
constexpr double kFinerFlipShare = 0.25;
// A part whose chosen quads stay flipped against the surface (it folds within a quad: thin sheets,
// small parts), also those of the finer density above (truck's part 30 at 2 000 quads: 7 flipped,
// 5 at half the edge length), takes its split triangles instead when they have no flipped quad and
// all such splits' quads, in component order, stay within this share of the quads made: small
// parts only (a large part keeps its regular quads, its flips reported).
constexpr double kFlipRescueShare = 0.1;
// ...and only parts of at most this many triangles are tried (each try decimates and untangles the
// part: on cycloidal's 117 parts, trying every flipped one cost 132 s of a 556 s run).
constexpr int kFlipRescueMaxTriangles = 1000;

// The smallest valid quad mesh of the component's topology, for a part of a remesh job whose
// layout gave no quads (a hole or handle narrower than a quad, a stage that failed): its triangles,
// decimated toward target_quads / 3 (topology and feature curves kept), each split into 3 quads
// (quad_extraction/split_triangles.h) and projected onto the input surface. While the split leaves
// quads flipped, the triangles are decimated to kSplitFacesGrowth times more faces, up to none
// removed or more than max_quads quads, while each step leaves fewer flipped (dragon-genus1 at
// 2 000 quads grew to all its 100 000 triangles, 60 000 quads, and kept 7 flipped). Throws
// Error(StageFailed) if the quads do not form a valid mesh.
constexpr double kSplitFacesGrowth = 4;
QuadChoice quads_of_split_triangles(const ComponentState& state, double target_quads, Progress& progress,
                                    double max_quads = std::numeric_limits<double>::infinity());

// The last rung for flipped quads, after the finer density and the split triangles above (which
// keep the part's quads regular, and closer to its surface: truck at 8 000 quads came within 1.55 %
// of the diagonal instead of 0.83 % when its parts 30, 52 and 53, with 5, 1 and 1 quads flipped,
// had them collapsed at the density asked instead of going to a finer one): the choice's quads
// that stay flipped against the surface, and slivers (quads with a collapsed edge among them), are
// untangled once more, then collapsed (quad_extraction/collapse_quads.h: a merge of two opposite
// corners, up to three irregular vertices each) on the surface they are measured against: the
// choice with them moved or collapsed, or nothing when none was.
std::optional<QuadChoice> collapse_folds(const ComponentState& state, const QuadChoice& choice, Progress& progress);

}  // namespace qgp
