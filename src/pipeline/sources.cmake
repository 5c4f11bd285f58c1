# Sources of the pipeline module (relative to this folder).
list(APPEND MODULE_SOURCES invariants.cpp mesh_region.cpp report.cpp check_options.cpp local_frame.cpp)
# mesh_region's stages: the candidate search over each part, the finishing sequence of a candidate, assembly
# and the report (pipeline/region_stages.h, pipeline/candidate.h).
list(APPEND MODULE_SOURCES mesh_parts.cpp candidates.cpp finish_candidate.cpp candidate_verdict.cpp
     candidate_quality.cpp patch_in_place.cpp assemble.cpp region_report.cpp mesh_report.cpp)
