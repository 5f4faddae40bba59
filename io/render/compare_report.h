#pragma once
/// \file compare_report.h
/// The files of `normalflow compare --report DIR`: compare.md, compare.csv, compare.json, and with
/// pictures the PNGs of io/render/comparison_pictures.h and an index.html that shows them under the table.
/// The text comes from lib/metrics/compare_report.h and io/util/report_json.h; this writes it.

#include <span>
#include <string>

#include "core/mesh.h"
#include "core/progress.h"
#include "metrics/compare_report.h"

namespace normalflow {

/// Options of write_compare_report.
struct CompareReportOptions {
    bool pictures = true;    ///< also render the PNG pictures and write index.html
    int picture_size = 400;  ///< width and height of each picture, pixels, 32..4096
};

/// What write_compare_report did.
struct CompareReportFiles {
    double pictures_seconds = -1.0;  ///< wall time of the pictures; -1 when none were drawn
};

/// Writes the report of r into dir (created if needed): compare.md (to_markdown), compare.csv
/// (to_csv), compare.json (to_json, one line), and with opt.pictures the pictures of
/// write_comparison_pictures(dir, reference, candidates) and index.html (to_html). Every file is
/// written atomically.
/// \param reference   the reference mesh; candidates: one mesh per row of r, same order (only read
///                    when opt.pictures)
/// \param progress    optional: gets begin("pictures") and progress(1) around the pictures
/// \throw IoError if the folder cannot be created or a file cannot be written; InvalidInput as
///        write_comparison_pictures for invalid meshes, or if candidates.size() != r.rows.size()
///        with pictures on.
CompareReportFiles write_compare_report(const std::string& dir, const CompareReport& r, const Mesh& reference,
                                        std::span<const Mesh> candidates, const CompareReportOptions& opt = {},
                                        Progress* progress = nullptr);

}  // namespace normalflow
