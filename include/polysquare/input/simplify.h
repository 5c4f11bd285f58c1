// Stage 1 (input, optional): simplification of curves far finer than the target size (coastlines), keeping the
// topology: no ring or curve may come to cross or touch another, and shared vertices are kept.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

/// Stage 1 as mesh_region runs it: which input vertices are corners, and how far curves finer than the size
/// are simplified first (the SimplifyOptions below are derived from these and the size). Fractions are of the size.
struct CurveOptions {
  double corner_threshold_deg = 30.0;  ///< input vertices turning by more than this are mesh nodes
  double simplify = 0.5;         ///< simplify curves finer than the size first: remove vertices whose triangle area
                                 ///< is below (simplify * size)^2, keeping topology and every vertex within size of
                                 ///< the simplified curve; the mesh follows the simplified curves (MeshResult::region)
                                 ///< and the report gives the largest distance moved and the area change; 0 = off
  double smooth_curves = 0.5;    ///< with simplify on: stretches of curve finer than the size are smoothed first,
                                 ///< each vertex kept within smooth * size of the input, so that digitisation steps
                                 ///< (a shoreline's 45-degree turns every 120 m) are not corners; 0 = off
  double min_island_width = 1.0; ///< with simplify on: holes, closed feature loops and faces between feature
                                 ///< pieces whose largest inscribed disk is narrower than this times size hold no
                                 ///< quad of that size: the hole or loop is left out, the face opened by removing
                                 ///< one of its pieces; each is reported (report `dropped_curves`, a CLI warning);
                                 ///< 0 keeps them all
  bool drop_small_parts = true;  ///< leave out (and report) polygon parts smaller than size^2
};

struct SimplifyOptions {
  double min_area = 0.0;  ///< Visvalingam-Whyatt: vertices whose triangle with their neighbours has an area below
                          ///< this are removed, smallest first (region units squared); 0 disables
  double max_distance = 0.0;  ///< a removal is skipped when an input vertex it replaces would lie farther than
                              ///< this from the new segment (region units); 0 = no bound
  double max_segment = 0.0;   ///< a removal is skipped when the new segment would be longer than this (region
                              ///< units): curves are coarsened to the target size, never beyond it, so smooth
                              ///< arcs keep turning gently; 0 = no bound (but see crowded_fraction)
  double crowded_fraction = 0.1;  ///< a vertex closer than this fraction of max_segment to a neighbour is removed
                                  ///< past max_segment (the shortcut is then at most 1 + this times it): two mesh
                                  ///< nodes that close leave an edge ratio no mesh can avoid
  double smooth_distance = 0.0;  ///< before vertices are removed, zigzags in stretches finer than max_segment are
                                 ///< smoothed: their vertices move towards their neighbours' mean, each within this
                                 ///< of the input curve (and max_distance of its own input point), never crossing or
                                 ///< closing in on another curve, so that digitisation steps stop being corners;
                                 ///< 0 = off
  double smooth_turn_deg = 15.0;  ///< a zigzag: a vertex turning more than this one way beside one turning the
                                  ///< other way; only zigzags and their neighbours move (arcs and islands, which
                                  ///< turn one way, would only shrink)
  double chord_reach = -1.0;  ///< the simplified curves keep their topology for the mesh edges too: ring vertices
                              ///< where a chord spanning up to this much of a ring could cross another curve
                              ///< become feature points (pin_chords_clear_of_curves, input/chord_clearance.h).
                              ///< Negative: max_segment (mesh edges along a ring are about the size; twice it
                              ///< pinned a fjord coast at 400 m more than needed: structured 0.970 instead of
                              ///< 0.986, with no overlap either way); 0: off
};

struct SimplifyStats {
  std::size_t vertices_before = 0, vertices_after = 0;
  std::size_t refused = 0;  ///< removals refused because the shortcut would cross or cover other geometry
  double max_distance = 0.0;  ///< largest distance of a removed vertex from the simplified curve (region units)
  std::size_t chord_pins = 0;  ///< ring vertices made feature points so that chords cross no curve (chord_reach)
};

/// A curve left out because the region it bounds is narrower than the size: no quad of that size fits there.
struct DroppedCurve {
  enum class Kind : std::uint8_t {
    hole,           ///< a hole ring (an island of a water domain)
    feature_loop,   ///< a closed feature curve (an island drawn as a feature)
    feature_piece,  ///< a piece of a feature curve between two crossings that closed a narrow face with other
                    ///< curves (two shorelines crossing twice within the size); the face joins its neighbour
    wedge_stretch,  ///< the start of a feature piece that left a meeting point at a small angle to another curve
                    ///< and ran within the size of it; the piece now leaves that curve where they are the size apart
  };
  Kind kind = Kind::hole;
  int source_feature = -1;  ///< input feature it came from (for messages)
  double width = 0.0;    ///< diameter of the largest disk inside the face it bounded (region units)
  double area = 0.0;     ///< that face's area (region units squared)
  double distance = 0.0; ///< feature pieces: largest distance of the piece from the curves that remain
  Vec2 at{};             ///< its first vertex
};

/// Removes holes and closed feature loops whose largest inscribed disk is narrower than `min_width` (a
/// shoreline at size h keeps every island wider than h). A ring or loop that shares a point with another curve,
/// or holds a feature point, stays. Ring and curve indices after the removed ones shift down; parts keep their
/// numbers (an outer ring is never removed). Returns what was removed, in input order.
std::vector<DroppedCurve> drop_narrow_islands(Region& region, double min_width);

/// Removes feature pieces (curves between crossings, as validation leaves them) that close a face of the curve
/// arrangement narrower than `min_width` with other curves, one at a time, so that the face joins the one across
/// the piece: of the face's pieces that separate it from another face, the one lying closest to the rest of its
/// boundary goes, and only if all of it lies within `min_width` of it. Faces holding other curves or feature
/// points, and faces outside the domain, are left alone. Returns what was removed.
std::vector<DroppedCurve> collapse_narrow_faces(Region& region, double min_width);

/// Opens wedges narrower than the size: where a feature piece leaves a meeting point (a crossing, or its end on a
/// ring) at less than `max_angle_deg` to another curve leaving the same point, its start runs within `min_width`
/// of that curve and no quad of that size fits between them. The piece's stretch up to its first vertex at least
/// `min_width` from the other curve is replaced by a straight link from the foot of that vertex on the other curve
/// (a new vertex there, the other curve split if it is a feature), unless the link would cross a curve. The
/// removed stretch lies within `min_width` of the other curve. Returns what was replaced (width = the angle's
/// opening at `min_width`, distance = the largest distance of the removed stretch from the other curve).
std::vector<DroppedCurve> open_narrow_wedges(Region& region, double min_width, double max_angle_deg = 20.0);

/// Diameter of the largest disk inside the simple polygon `ring` (either orientation), found to within
/// `tolerance`; the search stops as soon as a disk of diameter `enough` is found (0: no early stop), and a
/// polygon narrower than `enough` gets a diameter at most max(tolerance, enough / 10) below its own.
double inscribed_width(const std::vector<Vec2>& ring, double tolerance, double enough = 0.0);

/// Simplifies every ring and feature curve in place. Ring vertices where a feature ends, feature end points,
/// and enough vertices to keep each ring a triangle are never removed. A removal is refused when the new
/// segment would cross or touch another segment, or when the removed triangle would cover another vertex. Then
/// ring vertices are pinned where mesh edges could cross another curve (SimplifyOptions::chord_reach).
SimplifyStats simplify_region(Region& region, const SimplifyOptions& options);

}  // namespace polysquare
