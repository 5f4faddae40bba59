#pragma once
/// \file study_pairs.h
/// The noisy / ground-truth pairs of shared/data that the study benchmarks run on (nf_bench_study,
/// nf_bench_default).

#include <algorithm>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace normalflow::bench {

namespace fs = std::filesystem;

/// One noisy input with its ground truth and, where the data has one, a published result.
struct Pair {
    std::string set, noisy_name;  // e.g. "pairs_gnf", "fandisk_n0.3"
    fs::path noisy, truth;
    std::vector<std::pair<std::string, fs::path>> published;  // method label, result mesh
};

inline std::string published_label(const std::string& file) {
    if (file.find(".nllr_result") != std::string::npos) return "NLLR (published result, Li et al. 2018)";
    if (file.find(".gcn_result") != std::string::npos) return "GCN-Denoiser (published result, Shen et al. 2022)";
    return "published result";
}

/// Whether a benchmark's --only filters (substrings, none: everything) select the input named key.
inline bool selected(const std::vector<std::string>& only, const std::string& key) {
    return only.empty() || std::any_of(only.begin(), only.end(),
                                       [&](const std::string& o) { return key.find(o) != std::string::npos; });
}

/// The pairs of shared/data, following SOURCES.md: X_<noise>.ply with X_gt.ply in the same folder;
/// pairs_nllr's nicolo_i2 takes pairs_gnf/nicolo_gt.ply, and NLLR's julius result belongs to
/// pairs_gnf/julius_n0.2.ply (the same noisy mesh up to 1e-7).
inline std::vector<Pair> find_pairs(const fs::path& data) {
    std::vector<Pair> pairs;
    for (const char* set : {"pairs_gnf", "pairs_gcn", "pairs_nllr"}) {
        const fs::path dir = data / set;
        if (!fs::is_directory(dir)) continue;
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const fs::path& f : files) {
            const std::string stem = f.stem().string();
            if (f.extension() != ".ply" || stem.ends_with("_gt") || stem.find("result") != std::string::npos) continue;
            const auto us = stem.rfind('_');
            if (us == std::string::npos) continue;
            const std::string model = stem.substr(0, us);
            fs::path gt = dir / (model + "_gt.ply");
            if (!fs::exists(gt)) gt = data / "pairs_gnf" / (model + "_gt.ply");
            if (!fs::exists(gt)) continue;
            Pair p{set, stem, f, gt, {}};
            for (const fs::path& r : files) {
                const std::string rn = r.filename().string();
                if (rn.starts_with(stem + ".") && rn.find("_result") != std::string::npos)
                    p.published.emplace_back(published_label(rn), r);
            }
            if (stem == "julius_n0.2" && fs::exists(data / "pairs_nllr/julius_n2.nllr_result.ply"))
                p.published.emplace_back(published_label(".nllr_result"),
                                         data / "pairs_nllr/julius_n2.nllr_result.ply");
            pairs.push_back(std::move(p));
        }
    }
    return pairs;
}

}  // namespace normalflow::bench
