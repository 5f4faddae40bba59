#include "io/render/compare_report.h"

#include <filesystem>
#include <system_error>

#include "core/errors.h"
#include "io/render/comparison_pictures.h"
#include "io/util/atomic_file.h"
#include "io/util/report_json.h"

namespace normalflow {

namespace {

void write_text(const std::string& path, const std::string& text) {
    AtomicFile f(path, "compare");
    f.write(text);
    f.commit();
}

CompareReportPictures links(const ComparisonPictures& pic, int size) {
    CompareReportPictures l;
    l.size = size;
    l.views = pic.views;
    for (const MeshPictures& m : pic.meshes)
        l.meshes.push_back({m.shaded, m.distance, m.max_distance, m.clipped_fraction});
    l.legend = pic.legend;
    l.distance_max = pic.distance_max;
    l.percentile = pic.percentile;
    return l;
}

}  // namespace

CompareReportFiles write_compare_report(const std::string& dir, const CompareReport& r, const Mesh& reference,
                                        std::span<const Mesh> candidates, const CompareReportOptions& opt,
                                        Progress* progress) {
    CompareReportFiles out;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw IoError("compare: " + dir + ": cannot create the report folder: " + ec.message());
    const std::filesystem::path d(dir);
    write_text((d / "compare.md").string(), to_markdown(r));
    write_text((d / "compare.csv").string(), to_csv(r));
    write_text((d / "compare.json").string(), to_json(r).dump() + "\n");
    if (opt.pictures) {
        if (candidates.size() != r.rows.size())
            throw InvalidInput("write_compare_report: " + std::to_string(candidates.size()) + " candidate meshes for " +
                               std::to_string(r.rows.size()) + " rows");
        detail::begin(progress, "pictures");
        ComparisonPicturesOptions po;
        po.render.width = po.render.height = opt.picture_size;
        po.names.push_back(r.reference);  // the pictures are named after the files
        for (const CompareReportRow& row : r.rows) po.names.push_back(row.name);
        const ComparisonPictures pic = write_comparison_pictures(dir, reference, candidates, po);
        write_text((d / "index.html").string(), to_html(r, links(pic, opt.picture_size)));
        out.pictures_seconds = pic.seconds;
        if (progress) progress->progress(1.0);
    }
    return out;
}

}  // namespace normalflow
