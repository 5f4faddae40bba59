#pragma once
/// \file report_json.h
/// One JSON rendering per report type, for `--json` outputs and benchmark tables. Each function
/// returns an object whose keys are the report's field names (vectors as arrays); the normalflow
/// tool adds what only it knows (file names, read and write times).

#include "core/mesh_report.h"
#include "extract/extract_surface.h"
#include "io/cgal/cleanup.h"
#include "io/cgal/repair.h"
#include "io/util/json.h"
#include "normals/smooth.h"
#include "pipeline/pipeline.h"
#include "sdf/scan_convert.h"

namespace normalflow {

/// points_merged, degenerate_removed, duplicates_removed, faces_reversed, orientable,
/// patches_inverted, open_patches, warnings.
Json to_json(const RepairReport& r);

/// dims, voxel_size, origin, band_voxels, blocks, candidate_blocks, uncertain_sign,
/// winding_evaluations, tile_conflict_blocks, seconds_distance, seconds_sign, memory_bytes, warnings.
Json to_json(const ScanConvertReport& r);

/// iterations, seconds_per_iteration, band_voxels, allocated_voxels, normal_energy_start,
/// normal_energy, refit_energy_start, refit_energy, refit_steps, mu (Anisotropic only),
/// stopped_unchanged, seconds_normals, seconds_refit, seconds_reinit, warnings (the per-step
/// energy arrays are left out).
Json to_json(const SmoothReport& r);

/// vertices, triangles, closed, manifold.
Json to_json(const ExtractReport& r);

/// faces_before, faces_after, vertices_before, vertices_after, degenerate_removed,
/// components_removed, faces_in_removed_components, components_reversed, hausdorff,
/// result_to_input, input_to_result, closed, manifold, self_intersections,
/// self_intersections_found, seconds, warnings.
Json to_json(const cgal::CleanupReport& r);

/// vertices (welded), input_vertices, referenced_vertices, triangles (= faces), edges, components,
/// boundary_edges, non_manifold_edges, non_manifold_vertices, degenerate_faces, collapsed_faces,
/// duplicate_faces, inconsistent_edges, closed, manifold, oriented, euler_characteristic, area,
/// volume, bbox [min x, y, z, max x, y, z], warnings.
Json to_json(const MeshReport& r);
/// decimator, fallback, faces and vertices before and after, hausdorff, result_to_input,
/// input_to_result, closed, manifold, self_intersections (-1: not checked), repaired_self_intersections,
/// seconds_decimate, seconds,
/// warnings.
Json to_json(const DecimationReport& r);

/// repair (when repaired), distance, memory_estimate_bytes, voxelize (the scan report plus
/// band_half_width as run), smooth (when smoothed), extract, sharpen {vertices, moved, refused, restored,
/// mean_move, max_move, seconds} (when sharpened), decimate (when decimated),
/// seconds {repair, voxelize, smooth, extract, decimate, total}, peak_memory_bytes, warnings.
Json to_json(const PipelineReport& r);

/// Every parameter of a run of smooth_mesh (or of one of its halves, or of smooth_volume_input): o as given, with what the run resolved
/// from r where o left it to the run (the automatic resolution (0 for a volume input), the band rule, the length unit in world units, the
/// mode's iterations, normal steps and refit steps; the memory limit that applied). Keys as the command line's
/// flags, with '_' for '-': resolution, voxel_size, band, shell, repair, distance, max_memory, threads, mode,
/// iterations, normal_steps, length_scale, sigma_spatial, sigma_range, tv_lambda, mu, alpha, presmooth,
/// mu_robust, normal_dt, refit_steps, refit_dt, refit_tolerance, refit_super_steps, extend_by_gather,
/// all_samples, preserve_volume, second_order, active_band, connectivity, closed, fit_to_normal_map,
/// projection_steps, relax_steps, fit_steps, boundary_rings, iso, sharpen, target_faces, max_error, decimator.
/// Without o.smoothing (voxelize, extract) the engine's keys are left out.
/// voxel_size: the grid's (a scan conversion's, r.scan.grid; a volume input's own).
Json parameters_json(const PipelineOptions& o, const PipelineReport& r, double voxel_size);

}  // namespace normalflow
