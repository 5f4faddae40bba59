// normalflow compress IN OUT.(drc|glb): a mesh written as Draco, with the Draco options of the options table
// (pipeline/options.h, group WebOutput).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "cli_options.h"
#include "commands.h"
#include "core/errors.h"
#include "io/io.h"

namespace normalflow::cli {
namespace {

struct CompressArgs {
    std::string input, output;
    RunOptions run = default_options(Command::Compress);  ///< its Draco settings
    OutputFlags out;
};

int run_compress(const CompressArgs& a) {
    Stopwatch clock;
    const MeshFormat f = mesh_format_from_path(a.output);
    if (f != MeshFormat::Drc && f != MeshFormat::Glb)
        throw InvalidInput("compress: " + a.output + ": output must be .drc or .glb");
    const Mesh m = read_mesh(a.input);
    const double t_read = clock.lap();
    WriteOptions wo;
    wo.glb = GlbEncoding::Draco;
    wo.draco = a.run.draco;
    write_mesh(a.output, m, wo);
    const double t_write = clock.lap();
    const auto in_bytes = std::filesystem::file_size(a.input);
    const auto out_bytes = std::filesystem::file_size(a.output);
    // Raw size: float32 positions, normals and texture coordinates, 8-bit RGBA colours, uint32 indices.
    const std::size_t raw = m.positions.size() * 12 + m.normals.size() * 12 + m.colors.size() * 4 +
                            m.texcoords.size() * 8 + m.triangles.size() * 12;
    if (a.out.json) {
        Json j = Json::object();
        j.set("command", "compress")
            .set("input", a.input)
            .set("output", a.output)
            .set("vertices", m.positions.size())
            .set("triangles", m.triangles.size())
            .set("bytes_before", static_cast<std::size_t>(in_bytes))
            .set("bytes_raw", raw)
            .set("bytes_after", static_cast<std::size_t>(out_bytes))
            .set("attributes", Json::array(attribute_names(m)))
            .set("parameters", parameters_json(a.run, Command::Compress))
            .set("seconds_read", t_read)
            .set("seconds_compress", t_write);
        std::printf("%s\n", j.dump().c_str());
    } else if (!a.out.quiet) {
        std::printf("compress: %s (%zu bytes) -> %s (%zu bytes, %.1fx; raw %zu bytes%s%s) in %.3f s\n", a.input.c_str(),
                    static_cast<std::size_t>(in_bytes), a.output.c_str(), static_cast<std::size_t>(out_bytes),
                    out_bytes ? double(in_bytes) / double(out_bytes) : 0.0, raw, m.has_attributes() ? "; with " : "",
                    m.has_attributes() ? attribute_words(m).c_str() : "", t_write);
    }
    return 0;
}

}  // namespace

void add_compress_command(CLI::App& app) {
    auto a = std::make_shared<CompressArgs>();
    auto* cmd = app.add_subcommand("compress", "write a mesh as Draco (.drc) or Draco-compressed glTF (.glb)");
    cmd->add_option("IN", a->input, "mesh file")->required();
    cmd->add_option("OUT", a->output, "output .drc or .glb")->required();
    add_run_options(cmd, a->run, Command::Compress, a->out);
    on_run(cmd, a, run_compress);
}

}  // namespace normalflow::cli
