// normalflow batch IN... --output-dir DIR: smooth (the pipeline of `normalflow smooth`, the same flags) over files,
// folders (their mesh and volume files) and lists of files (--list), several files at once (--jobs).
// - One JSON line per file on stdout as it finishes: {"file", "output", "status": ok|skipped|failed, ...}, and a
//   summary line at the end ({"summary": {...}}); without --json, one text line per file.
// - A failure is its file's: the error is reported on its line and the others go on. The exit status is 0 when
//   every file is done (or skipped), 1 when one failed, 130 when interrupted.
// - Resumable: an output that exists is complete (every output is written whole or not at all), so its file is
//   skipped; --overwrite redoes it. A run stopped with Ctrl-C leaves no partial output.
// - The result of a file does not depend on --jobs or --threads.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cli_options.h"
#include "commands.h"
#include "core/errors.h"
#include "core/version.h"
#include "io/io.h"
#include "pipeline/options.h"
#include "pipeline/pipeline.h"
#include "pipeline/report_json.h"
#include "pipeline/run_file.h"

namespace normalflow::cli {

namespace {

namespace fs = std::filesystem;

struct BatchArgs {
    std::vector<std::string> inputs;  ///< files and folders
    std::string list;                 ///< a file with one input path per line
    std::string output_dir;
    std::string format = "ply";
    bool recursive = false;
    bool overwrite = false;
    unsigned jobs = 1;
    RunOptions run = default_options(Command::Smooth);  ///< smooth's options
    OutputFlags out;
};

struct Job {
    std::string input, output;
};

bool is_input_path(const std::string& p) {
    return is_volume_path(p) || mesh_format_from_path(p) != MeshFormat::Unknown;
}

/// The file name without its extension (both of .nii.gz).
std::string stem_of(const fs::path& p) {
    std::string name = p.filename().string();
    for (const char* ext : {".nii.gz", ".NII.GZ"})
        if (name.size() > std::strlen(ext) && name.compare(name.size() - std::strlen(ext), std::string::npos, ext) == 0)
            return name.substr(0, name.size() - std::strlen(ext));
    return p.stem().string();
}

/// Every input file with its output path; folders give their mesh and volume files (sorted), mirrored under DIR.
std::vector<Job> plan(const BatchArgs& a) {
    std::vector<std::string> inputs = a.inputs;
    if (!a.list.empty()) {
        std::ifstream in(a.list);
        if (!in) throw IoError(a.list + ": cannot read the list of files");
        for (std::string line; std::getline(in, line);) {
            while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
            if (!line.empty() && line[0] != '#') inputs.push_back(line);
        }
    }
    if (inputs.empty()) throw InvalidInput("no input: give files, folders or --list");
    std::vector<Job> jobs;
    const fs::path out_dir(a.output_dir);
    const std::string ext = "." + a.format;
    for (const std::string& in : inputs) {
        std::error_code ec;
        if (fs::is_directory(in, ec)) {
            std::vector<fs::path> found;
            const auto take = [&](const fs::directory_entry& e) {
                if (e.is_regular_file() && is_input_path(e.path().string())) found.push_back(e.path());
            };
            if (a.recursive)
                for (const auto& e : fs::recursive_directory_iterator(in)) take(e);
            else
                for (const auto& e : fs::directory_iterator(in)) take(e);
            std::sort(found.begin(), found.end());
            for (const fs::path& p : found) {
                const fs::path rel = fs::relative(p.parent_path(), in);
                jobs.push_back({p.string(), (out_dir / rel / (stem_of(p) + ext)).lexically_normal().string()});
            }
        } else {
            // a file that is missing or unreadable fails on its own line; an unknown extension is refused now
            if (!is_input_path(in))
                throw InvalidInput(in +
                                   ": not a mesh or volume file (obj, ply, off, stl, gltf, glb, drc; vdb, nrrd, "
                                   "nhdr, nii, nii.gz)");
            jobs.push_back({in, (out_dir / (stem_of(fs::path(in)) + ext)).lexically_normal().string()});
        }
    }
    std::map<std::string, std::string> by_output;
    std::set<std::string> input_set;
    for (const Job& j : jobs) input_set.insert(fs::weakly_canonical(j.input).string());
    for (const Job& j : jobs) {
        const auto [it, fresh] = by_output.emplace(j.output, j.input);
        if (!fresh) throw InvalidInput(j.input + " and " + it->second + " would both be written to " + j.output);
        if (input_set.count(fs::weakly_canonical(j.output).string()))
            throw InvalidInput(j.output + " is an input file; choose another --output-dir");
    }
    return jobs;
}

/// Stops every job on Ctrl-C.
struct InterruptOnly : Progress {
    bool should_stop() override { return interrupted(); }
};

/// Smooths one file into its output: the library's run_file, as `normalflow smooth` runs it; its report is the
/// JSON line's "result".
FileRun smooth_file(const Job& job, const RunOptions& run, std::size_t memory_share) {
    InterruptOnly progress;
    fs::create_directories(fs::path(job.output).parent_path());
    return run_file(Command::Smooth, job.input, job.output, run, &progress, memory_share);
}

int run_batch(const BatchArgs& a) {
    Stopwatch total;
    validate(pipeline_options(a.run, Command::Smooth));
    if (mesh_format_from_path("x." + a.format) == MeshFormat::Unknown)
        throw InvalidInput("--format " + a.format + ": expected ply, obj, off, stl, glb or drc");
    const std::vector<Job> jobs = plan(a);
    const unsigned workers = std::max(1u, std::min<unsigned>(a.jobs, unsigned(jobs.size())));
    // Files at once share the memory: each run is checked against its part of what is available.
    const std::size_t memory_share = available_memory_bytes() / workers;

    std::mutex out_mutex;
    std::size_t done = 0, ok = 0, skipped = 0, failed = 0;
    const bool show = !a.out.quiet && !a.out.json && isatty(fileno(stderr));
    // One line per file: the JSON object, or the text.
    const auto report_line = [&](const Job& job, const char* status, Json j, const std::string& text) {
        std::lock_guard lock(out_mutex);
        ++done;
        (std::string(status) == "ok" ? ok : std::string(status) == "skipped" ? skipped : failed)++;
        if (a.out.json)
            std::printf("%s\n", j.dump().c_str());
        else if (!a.out.quiet)
            std::printf("%s %s -> %s%s\n", status, job.input.c_str(), job.output.c_str(), text.c_str());
        std::fflush(stdout);
        if (show) std::fprintf(stderr, "batch: %zu of %zu files\n", done, jobs.size());
    };
    const auto line = [](const Job& job, const char* status, double seconds) {
        Json j = Json::object();
        j.set("file", job.input).set("output", job.output).set("status", status).set("seconds", seconds);
        return j;
    };

    std::atomic<std::size_t> next{0};
    const auto worker = [&] {
        for (std::size_t i; (i = next++) < jobs.size();) {
            const Job& job = jobs[i];
            if (interrupted()) return;
            std::error_code ec;
            if (!a.overwrite && fs::exists(job.output, ec)) {
                report_line(job, "skipped", line(job, "skipped", 0).set("reason", "the output exists"),
                            " (the output exists)");
                continue;
            }
            Stopwatch clock;
            try {
                FileRun f = smooth_file(job, a.run, memory_share);
                const std::size_t triangles = f.triangles;
                const double seconds = clock.seconds();
                Json l = line(job, "ok", seconds);
                l.set("triangles", triangles).set("result", std::move(f.report));
                char text[64];
                std::snprintf(text, sizeof text, " (%zu triangles, %.1f s)", triangles, seconds);
                report_line(job, "ok", std::move(l), text);
            } catch (...) {
                const ErrorStatus e = error_status(std::current_exception());
                if (e.status == 130) return;  // Ctrl-C: the file is neither done nor failed
                std::string message = e.message;
                if (message.find(job.input) == std::string::npos) message = job.input + ": " + message;
                report_line(job, "failed",
                            line(job, "failed", clock.seconds()).set("error", message).set("exit_status", e.status),
                            ": " + message);
            }
        }
    };
    std::vector<std::thread> pool;
    for (unsigned w = 1; w < workers; ++w) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();

    const bool stopped = interrupted() && done < jobs.size();
    if (a.out.json) {
        Json s = Json::object();
        s.set("files", jobs.size())
            .set("ok", ok)
            .set("skipped", skipped)
            .set("failed", failed)
            .set("not_run", jobs.size() - done)
            .set("interrupted", stopped)
            .set("jobs", workers)
            .set("seconds", total.seconds())
            .set("version", version());
        std::printf("%s\n", Json::object().set("summary", s).dump().c_str());
    } else if (!a.out.quiet) {
        std::printf("batch: %zu files: %zu done, %zu skipped (output exists), %zu failed%s, %.1f s\n", jobs.size(), ok,
                    skipped, failed, stopped ? ", interrupted" : "", total.seconds());
    }
    if (stopped) throw Cancelled("batch: cancelled");
    return failed > 0 ? 1 : 0;
}

}  // namespace

void add_batch_command(CLI::App& app) {
    auto a = std::make_shared<BatchArgs>();
    auto* cmd = app.add_subcommand(
        "batch",
        "smooth many files (as `smooth`, the same flags): one JSON line per file with --json, a failure "
        "kept to its file, outputs that exist skipped (resumable), several files at once (--jobs)");
    cmd->add_option("IN", a->inputs, "mesh or volume files, and folders of them");
    cmd->add_option("--list", a->list, "a file naming one input per line (# starts a comment)");
    cmd->add_option("-o,--output-dir", a->output_dir, "where the results go, as NAME.FORMAT (mirroring folders)")
        ->required();
    cmd->add_option("--format", a->format, "output format: ply, obj, off, stl, glb, drc")->capture_default_str();
    cmd->add_flag("-r,--recursive", a->recursive, "take the files of folders' subfolders too");
    cmd->add_flag("--overwrite", a->overwrite, "redo files whose output exists (default: skip them)");
    cmd->add_option("-j,--jobs", a->jobs, "files at once (each uses the threads; results do not depend on it)")
        ->check(CLI::Range(1u, 1024u))
        ->capture_default_str();
    add_run_options(cmd, a->run, Command::Smooth, a->out);
    on_run(cmd, a, run_batch);
}

}  // namespace normalflow::cli
