#include "pipeline/report_json.h"

#include <algorithm>
#include <vector>

namespace normalflow {

Json to_json(const RepairReport& r) {
    Json j = Json::object();
    j.set("points_merged", r.points_merged)
        .set("degenerate_removed", r.degenerate_removed)
        .set("duplicates_removed", r.duplicates_removed)
        .set("faces_reversed", r.faces_reversed)
        .set("orientable", r.orientable)
        .set("patches_inverted", r.patches_inverted)
        .set("open_patches", r.open_patches)
        .set("warnings", Json::array(r.warnings));
    return j;
}

Json to_json(const ScanConvertReport& r) {
    Json j = Json::object();
    j.set("dims", Json::array(std::vector<int>(r.grid.dims.begin(), r.grid.dims.end())))
        .set("voxel_size", r.grid.voxel_size)
        .set("origin", Json::array(std::vector<double>{r.grid.origin.x, r.grid.origin.y, r.grid.origin.z}))
        .set("band_voxels", r.band_voxels)
        .set("blocks", r.blocks)
        .set("candidate_blocks", r.candidate_blocks)
        .set("uncertain_sign", r.uncertain_sign)
        .set("winding_evaluations", r.winding_evaluations)
        .set("tile_conflict_blocks", r.tile_conflict_blocks)
        .set("seconds_distance", r.seconds_distance)
        .set("seconds_sign", r.seconds_sign)
        .set("memory_bytes", r.memory_bytes)
        .set("warnings", Json::array(r.warnings));
    return j;
}

Json to_json(const SmoothReport& r) {
    // Per-iteration records as one array per field (the CLI's --json contract since the first
    // release; scripts index them by iteration).
    std::vector<double> seconds, g0, g1, d0, d1;
    std::vector<std::size_t> band, allocated, points;
    std::vector<int> steps, evals;
    std::vector<float> mu, shift, rough;
    for (const SmoothIteration& it : r.iterations) {
        shift.push_back(it.volume_shift);
        rough.push_back(it.roughness);
        seconds.push_back(it.seconds);
        band.push_back(it.band_voxels);
        allocated.push_back(it.allocated_voxels);
        points.push_back(it.filter_points);
        if (!it.normal_energy.empty()) {  // mean curvature flow has no normal loop and no refit
            g0.push_back(it.normal_energy_start());
            g1.push_back(it.normal_energy_end());
        }
        if (!it.refit_energy.empty()) {
            d0.push_back(it.refit_energy_start());
            d1.push_back(it.refit_energy_end);
        }
        if (!it.refit_energy.empty() || it.refit_evaluations > 0) {  // bricks: the most of any brick, no energies
            steps.push_back(it.refit_steps);
            evals.push_back(it.refit_evaluations);
        }
        if (it.mu > 0) mu.push_back(it.mu);
    }
    Json j = Json::object();
    j.set("iterations", r.iterations_run())
        .set("seconds_per_iteration", Json::array(seconds))
        .set("band_voxels", Json::array(band))
        .set("allocated_voxels", Json::array(allocated))
        .set("normal_energy_start", Json::array(g0))
        .set("normal_energy", Json::array(g1))
        .set("refit_energy_start", Json::array(d0))
        .set("refit_energy", Json::array(d1))
        .set("refit_steps", Json::array(steps))
        .set("refit_evaluations", Json::array(evals));
    if (std::any_of(points.begin(), points.end(), [](std::size_t n) { return n > 0; }))
        j.set("filter_points", Json::array(points));
    if (!mu.empty()) j.set("mu", Json::array(mu));
    j.set("volume_shift", Json::array(shift)).set("roughness", Json::array(rough));
    j.set("stopped_unchanged", r.stopped_unchanged)
        .set("stopped_smooth", r.stopped_smooth)
        .set("stopped_at_checkpoint", r.stopped_at_checkpoint)
        .set("seconds_normals", r.seconds_normals)
        .set("seconds_refit", r.seconds_refit)
        .set("seconds_reinit", r.seconds_reinit)
        .set("warnings", Json::array(r.warnings));
    return j;
}

Json to_json(const ExtractReport& r) {
    Json j = Json::object();
    j.set("vertices", r.vertices).set("triangles", r.triangles).set("closed", r.closed).set("manifold", r.manifold);
    return j;
}

Json to_json(const cgal::CleanupReport& r) {
    Json j = Json::object();
    j.set("faces_before", r.faces_before)
        .set("faces_after", r.faces_after)
        .set("vertices_before", r.vertices_before)
        .set("vertices_after", r.vertices_after)
        .set("degenerate_removed", r.degenerate_removed)
        .set("components_removed", r.components_removed)
        .set("faces_in_removed_components", r.faces_in_removed_components)
        .set("components_reversed", r.components_reversed)
        .set("hausdorff", r.hausdorff)
        .set("result_to_input", r.result_to_input)
        .set("input_to_result", r.input_to_result)
        .set("closed", r.closed)
        .set("manifold", r.manifold)
        .set("self_intersections", r.self_intersections)
        .set("self_intersections_found", r.self_intersections_found)
        .set("seconds", r.seconds)
        .set("warnings", Json::array(r.warnings));
    return j;
}

Json to_json(const DecimationReport& r) {
    Json j = Json::object();
    j.set("decimator", r.decimator)
        .set("fallback", r.fallback)
        .set("faces_before", r.faces_before)
        .set("faces_after", r.faces_after)
        .set("vertices_before", r.vertices_before)
        .set("vertices_after", r.vertices_after)
        .set("hausdorff", r.hausdorff)
        .set("result_to_input", r.result_to_input)
        .set("input_to_result", r.input_to_result)
        .set("closed", r.closed)
        .set("manifold", r.manifold)
        .set("self_intersections", r.self_intersections)
        .set("repaired_self_intersections", r.repaired_self_intersections)
        .set("seconds_decimate", r.seconds_decimate)
        .set("seconds", r.seconds)
        .set("warnings", Json::array(r.warnings));
    return j;
}

Json to_json(const MeshReport& r) {
    Json j = Json::object();
    j.set("vertices", r.vertices)
        .set("input_vertices", r.input_vertices)
        .set("referenced_vertices", r.referenced_vertices)
        .set("triangles", r.faces)
        .set("edges", r.edges)
        .set("components", r.components)
        .set("boundary_edges", r.boundary_edges)
        .set("boundary_loops", r.boundary_loops)
        .set("non_manifold_edges", r.non_manifold_edges)
        .set("non_manifold_vertices", r.non_manifold_vertices)
        .set("degenerate_faces", r.degenerate_faces)
        .set("collapsed_faces", r.collapsed_faces)
        .set("duplicate_faces", r.duplicate_faces)
        .set("inconsistent_edges", r.inconsistent_edges)
        .set("closed", r.closed)
        .set("manifold", r.manifold)
        .set("oriented", r.oriented)
        .set("euler_characteristic", r.euler_characteristic)
        .set("area", r.area)
        .set("volume", r.volume);
    Json box = Json::array();
    for (double c : {r.bbox.min.x, r.bbox.min.y, r.bbox.min.z, r.bbox.max.x, r.bbox.max.y, r.bbox.max.z}) box.push(c);
    j.set("bbox", box).set("warnings", Json::array(r.warnings));
    return j;
}

Json to_json(const PipelineReport& r) {
    Json j = Json::object();
    if (r.repaired) j.set("repair", to_json(r.repair));
    j.set("distance", to_string(r.distance)).set("memory_estimate_bytes", r.memory_estimate_bytes);
    Json vox = to_json(r.scan);
    vox.set("band_half_width", r.scan_options.half_width);
    j.set("voxelize", vox);
    if (r.smoothed) j.set("smooth", to_json(r.smooth)).set("length_scale", r.length_scale);
    if (r.bricked) {
        const BrickReport& b = r.bricks;
        Json n = Json::array();
        for (int c : b.bricks) n.push(c);
        j.set("bricks", Json::object()
                            .set("brick_voxels", b.brick_voxels)
                            .set("halo_voxels", b.halo_voxels)
                            .set("bricks", n)
                            .set("bricks_run", b.bricks_run)
                            .set("iterations", b.passes)
                            .set("largest_window_blocks", b.largest_window_blocks)
                            .set("estimated_window_blocks", r.estimated_window_blocks)
                            .set("seconds_scan", b.seconds_scan)
                            .set("seconds_smooth", b.seconds_smooth)
                            .set("refit_passes_redone", b.refit_passes_redone)
                            .set("refit_passes_windowed", b.refit_passes_windowed)
                            .set("refit_explicit_tails", b.refit_explicit_tails)
                            .set("compact_band", b.compact_band)
                            .set("ran", b.elsewhere ? "elsewhere" : "here"));
    }
    if (r.smoothed || r.noise > 0) j.set("noise", r.noise);
    j.set("connectivity", r.connectivity_kept ? "kept" : "remeshed");
    if (!r.keep_declined.empty()) j.set("keep_declined", r.keep_declined);
    if (r.fitted) {
        Json f = Json::object();
        f.set("vertices", r.fit.vertices)
            .set("boundary_vertices", r.fit.boundary_vertices)
            .set("outside_band", r.fit.outside_band)
            .set("mean_distance", r.fit.mean_distance)
            .set("max_distance", r.fit.max_distance)
            .set("mean_face_angle_deg", r.fit.mean_face_angle_deg);
        if (r.connectivity_kept) f.set("restored", r.fit_restored);
        j.set("fit", f);
    }
    if (r.faces_filtered)
        j.set("face_filter", Json::object()
                                 .set("faces", r.faces.faces)
                                 .set("rounds", r.faces.rounds)
                                 .set("rounds_run", r.faces.rounds_run)
                                 .set("blend", r.faces.blend)
                                 .set("salient", r.faces.salient)
                                 .set("guided", r.faces.guided)
                                 .set("estimated_error", r.faces.estimated_error)
                                 .set("rms_displacement", r.faces.rms_displacement)
                                 .set("reverted_moves", r.faces.reverted_moves)
                                 .set("restored", r.fit_restored));
    if (r.untangled) {
        const auto one = [](const UntangleReport& u) {
            return Json::object()
                .set("folded_before", u.folded_before)
                .set("folded_after", u.folded_after)
                .set("moved", u.moved)
                .set("passes", u.passes)
                .set("undone", u.undone);
        };
        j.set("untangle", Json::object().set("input", one(r.untangle_input)).set("filtered", one(r.untangle_filtered)));
    }
    if (!r.connectivity_kept) j.set("extract", to_json(r.extract));
    if (r.sharpened) {
        const SharpenReport& h = r.sharpen;
        j.set("sharpen", Json::object()
                             .set("vertices", h.vertices)
                             .set("moved", h.moved)
                             .set("refused", h.refused)
                             .set("restored", r.sharpen_restored)
                             .set("mean_move", h.mean_move)
                             .set("max_move", h.max_move)
                             .set("seconds", h.seconds));
    }
    if (r.trimmed) {
        Json t = Json::object();
        t.set("faces_removed", r.trim.faces_removed).set("components_removed", r.trim.components_removed);
        j.set("trim", t);
    }
    if (!r.connectivity_kept && r.components.components > 0)
        j.set("components", Json::object()
                                .set("input", r.components.allowed)
                                .set("extracted", r.components.components)
                                .set("removed", r.components.removed)
                                .set("faces_removed", r.components.faces));
    if (r.decimated) j.set("decimate", to_json(r.decimate).set("default", r.compacted));
    if (r.checked) {
        Json c = Json::object();
        c.set("closed", r.output.closed)
            .set("manifold", r.output.manifold)
            .set("degenerate_faces", r.output.degenerate_faces)
            .set("components", r.output.components)
            .set("self_intersecting_pairs", r.output_self_intersections);
        if (r.connectivity_kept)
            c.set("input_self_intersecting_pairs", r.input_self_intersections)
                .set("flipped_faces", r.flipped_faces)
                .set("input_flipped_faces", r.input_flipped_faces);
        j.set("checked", c);
    }
    Json s = Json::object();
    s.set("repair", r.seconds.repair)
        .set("voxelize", r.seconds.voxelize)
        .set("smooth", r.seconds.smooth)
        .set("extract", r.seconds.extract)
        .set("decimate", r.seconds.decimate)
        .set("total", r.seconds.total);
    j.set("seconds", s).set("peak_memory_bytes", r.peak_memory_bytes).set("warnings", Json::array(r.warnings));
    return j;
}

Json parameters_json(const PipelineOptions& o, const PipelineReport& r, double voxel_size) {
    const ScanConvertOptions& scan = r.scan_options;  // as run: the automatic resolution and the band rule applied
    SmoothOptions s = o.smooth;  // with the length unit as run, in voxels, for the mode's refit steps
    if (s.length_scale == 0 && r.length_scale > 0 && voxel_size > 0)
        s.length_scale = float(r.length_scale / voxel_size);
    Json j = Json::object();
    j.set("resolution", scan.voxel_size > 0 || !r.scan.grid.voxel_size ? 0 : scan.resolution)
        .set("voxel_size", voxel_size)
        .set("band", scan.half_width)
        .set("shell", scan.shell_thickness)
        .set("repair", o.repair)
        .set("distance", to_string(o.distance))
        .set("max_memory", static_cast<unsigned long long>(o.max_memory_bytes))
        .set("threads", scan.threads);
    if (o.smoothing) {
        j.set("mode", to_string(s.mode))
            .set("iterations", s.iterations > 0 ? s.iterations : default_iterations(s.mode))
            .set("normal_steps", s.normal_steps > 0 ? s.normal_steps : default_normal_steps(s.mode))
            .set("length_scale", r.length_scale)
            .set("sigma_spatial", r.sigma_spatial > 0 ? r.sigma_spatial : double(s.sigma_spatial))
            .set("sigma_range", s.sigma_range)
            .set("tv_lambda", s.tv_lambda)
            .set("mu", s.mu)
            .set("alpha", s.alpha)
            .set("presmooth", s.conductance_presmooth_steps)
            .set("mu_robust", s.mu_robust)
            .set("normal_dt", s.normal_dt)
            .set("refit_steps", s.refit_max_steps > 0 ? s.refit_max_steps : default_refit_steps(s))
            .set("refit_dt", s.refit_dt)
            .set("refit_tolerance", s.refit_tolerance)
            .set("refit_super_steps", s.refit_super_steps)
            .set("extend_by_gather", s.extend_by_gather)
            .set("all_samples", !s.thin_samples)
            .set("preserve_volume", s.preserve_volume)
            .set("second_order", s.second_order_term)
            .set("active_band", s.active_band);
    }
    j.set("connectivity", to_string(o.connectivity))
        .set("closed", o.closed)
        .set("fit_to_normal_map", o.fit_to_normal_map)
        .set("projection_steps", o.fit.projection_steps)
        .set("relax_steps", o.fit.relax_steps)
        .set("fit_steps", o.fit.vertex_steps)
        .set("keep_filter", to_string(o.keep_filter))
        .set("face_steps", o.faces.normal_steps)
        .set("boundary_rings", o.fit.boundary_rings)
        .set("iso", o.extract.iso)
        .set("sharpen", o.sharpen)
        .set("target_faces", o.target_faces)
        .set("max_error", o.max_error)
        .set("full_density", o.full_density)
        .set("decimator", to_string(o.decimator));
    return j;
}

}  // namespace normalflow
