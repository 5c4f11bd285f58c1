// Stage 1 (input): ring vertices made mesh nodes where a mesh edge, a chord between two boundary nodes, could
// cross another curve. Each polygon part is meshed alone with boundary edges that are chords of its rings; where a
// ring is concave towards another curve closer than a chord's sagitta (an island in a hole, two parts beside each
// other, the two shores of a narrow inlet), the chord cuts across that curve and the meshes overlap.
#pragma once

#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

/// Adds to region.feature_points (which become mesh nodes) ring vertices such that every chord between two points
/// of a ring no more than `reach` apart along it, with no mesh node forced between them (a feature point, added or
/// given, a feature's end, a point the ring shares with another ring), lies in a convex hull of ring points whose
/// interior no other curve enters (other rings, feature curves, the rest of the same ring). A chord from node to
/// node inside such a hull cannot cross another curve, nor a chord of it. Walking each ring, a vertex is pinned
/// only where the stretch since the last node turns unclear (greedy: as few pins as that start allows). `reach`
/// is the longest arc a mesh boundary edge spans (simplify_region: the size); longer edges are not covered (the
/// overlap invariant refuses a mesh where one crosses). Rings
/// whose chords are all clear get nothing: convex rings facing each other, straight stretches. Run it on the rings
/// the mesh follows (after simplification). Returns the vertices added, ring by ring, in ring order.
std::vector<Vec2> pin_chords_clear_of_curves(Region& region, double reach);

}  // namespace polysquare
