// Option values checked before any work, next to the options structs whose defaults they guard.
#pragma once

#include <string>

#include "polysquare/core/region.h"
#include "polysquare/pipeline/mesh_region.h"

namespace polysquare {

/// Largest MeshOptions::threads accepted (tbb's global_control takes any count; a billion ended in bad_alloc).
constexpr int kMaxThreads = 4096;

/// Throws InputError for an option value the pipeline cannot honour, naming the option (by its CLI flag and its
/// field) and the value: NaN or infinite values anywhere; size <= 0; min_scaled_jacobian outside [0, 1];
/// max_edge_ratio below 1; max_poor_fraction outside [0, 1]; corner_threshold_deg, refine.flat_corner_deg and refine.loop_corner_deg outside [0, 180]; simplify,
/// map.deform.boundary_weight and map.deform.feature_weight below 0; feature_tolerance < 0 (0 leaves the chords unbounded); max_quads 0;
/// threads outside [0, kMaxThreads]; parts below 0. A NaN gate would otherwise compare false and pass every mesh.
void check_mesh_options(const MeshOptions& options);

/// `options` with the sizes the stages read: a graded run (size.graded()) gets size.h = size.field.size_min, the
/// least size, which scales every stage's tolerances. Throws InputError when --size and --size-min disagree.
MeshOptions resolve_sizes(const MeshOptions& options);

/// Smallest size, in steps of double precision (ulp) at the region's largest coordinate, that a mesh keeps when
/// written back in the input's coordinates (an edge rounded by half a step each end turns by under 1e-3 rad).
constexpr double kMinSizeInSteps = 1024.0;

/// Throws InputError when `options.size` does not suit `region` (read and validated): larger than half the
/// region's smaller extent, smaller than kMinSizeInSteps steps of double precision at the region's largest
/// coordinate, or an estimated quad count (area / size^2) above options.max_quads or above what the machine's
/// available memory holds (check_quad_memory). Figures in the
/// messages are printed with 6 significant digits; a region whose extent or area is not a finite positive number
/// is refused as such. The message starts with region.source.
void check_mesh_size(const Region& region, const MeshOptions& options);

/// Throws InputError (naming --max-quads, starting with `source`) when a graded run's field needs more quads
/// than options.size.max_quads by its estimate (SizeFieldStats::estimated_quads), or more than the machine's
/// available memory holds (check_quad_memory).
void check_field_estimate(double estimated_quads, const MeshOptions& options, const std::string& source);

/// Memory a mesh takes per quad while it is made, at least. Measured (peak resident set / quads, one thread): a
/// 1000 x 1000 square at size 1, 346 MB for 1.0M quads (346 bytes); data/cases/fjord_coast at size 14, 390 MB for
/// 1.05M quads (373 bytes). Rounded down, so that a run check_quad_memory refuses could not have fitted.
constexpr double kBytesPerQuad = 300.0;

/// Bytes of memory a run can still take: /proc/meminfo's MemAvailable plus SwapFree, else the free physical pages
/// (sysconf); 0 when unknown.
double available_memory_bytes();

/// Throws InputError when `estimated_quads` quads need more than `available_bytes` (kBytesPerQuad each; 0 =
/// unknown, never refused): a size whose quads --max-quads allows but the machine cannot hold is refused before
/// meshing, with what it would need, instead of growing until it is killed. `what` starts the message (the
/// source and the size option).
void check_quad_memory(double estimated_quads, double available_bytes, const std::string& what);

/// `v` with 6 significant digits ("1e+300", "0.25", "nan"): numbers in messages.
std::string short_number(double v);

}  // namespace polysquare
