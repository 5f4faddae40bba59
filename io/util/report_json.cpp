#include "io/util/report_json.h"

#include <vector>

namespace normalflow {

namespace {

Json row_json(const CompareReportRow& r) {
    const MeshComparison& c = r.comparison;
    Json j = Json::object();
    j.set("candidate", r.name);
    j.set("hausdorff", c.distance.hausdorff).set("hausdorff_relative", c.hausdorff_relative);
    j.set("mean_distance", c.distance.mean).set("mean_relative", c.mean_relative);
    j.set("rms_distance", c.distance.rms).set("rms_relative", c.rms_relative);
    j.set("max_candidate_to_reference", c.distance.max_a_to_b).set("max_reference_to_candidate", c.distance.max_b_to_a);
    j.set("mean_normal_angle_deg", c.distance.mean_normal_angle_deg);
    j.set("area", c.area_candidate).set("area_change", c.area_change);
    j.set("volume", c.volume_candidate).set("volume_change", c.volume_change);
    j.set("vertices", c.vertices_candidate).set("triangles", c.faces_candidate);
    j.set("components", c.components_candidate).set("closed", c.closed_candidate).set("manifold", c.manifold_candidate);
    if (r.self_intersections >= 0) j.set("self_intersecting_pairs", r.self_intersections);
    j.set("crease_preservation", c.crease.fraction).set("crease_mean_angle_deg", c.crease.mean_angle_deg);
    if (c.correspondence) {
        const CorrespondenceErrors& e = *c.correspondence;
        Json k = Json::object();
        k.set("faces", e.faces).set("degenerate_faces", e.degenerate_faces);
        k.set("mean_face_angle_deg", e.mean_face_angle_deg).set("max_face_angle_deg", e.max_face_angle_deg);
        k.set("vertices", e.vertices);
        k.set("mean_vertex_distance", e.mean_vertex_distance)
            .set("mean_vertex_distance_relative", e.mean_vertex_distance_relative);
        k.set("max_vertex_distance", e.max_vertex_distance)
            .set("max_vertex_distance_relative", e.max_vertex_distance_relative);
        j.set("correspondence", k);
    }
    j.set("seconds", r.seconds).set("warnings", Json::array(c.warnings));
    return j;
}

}  // namespace

Json to_json(const CompareReport& a) {
    const std::vector<CompareReportRow>& rows = a.rows;
    Json j = Json::object();
    j.set("command", "compare").set("reference", a.reference);
    if (!rows.empty()) {
        const MeshComparison& c = rows.front().comparison;
        Json ref = Json::object();
        ref.set("bbox_diagonal", c.reference_diagonal).set("area", c.area_reference).set("volume", c.volume_reference);
        ref.set("components", c.components_reference)
            .set("closed", c.closed_reference)
            .set("manifold", c.manifold_reference);
        ref.set("feature_edges", c.crease.feature_edges).set("feature_length", c.crease.feature_length);
        j.set("reference_stats", ref);
    }
    Json proto = Json::object();
    proto.set("samples_per_mesh", a.options.sampling.samples)
        .set("seed", static_cast<unsigned long long>(a.options.sampling.seed));
    proto.set("crease_angle_deg", a.options.crease.angle_deg)
        .set("crease_radius_relative", a.options.crease.radius_relative);
    if (a.options.correspondence)
        proto.set("correspondence", true);  // absent: the output without the flag is unchanged
    j.set("protocol", proto);
    Json arr = Json::array();
    for (const CompareReportRow& r : rows) arr.push(row_json(r));
    j.set("candidates", arr);
    return j;
}

}  // namespace normalflow
