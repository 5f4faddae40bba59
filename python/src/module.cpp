// normalflow._normalflow: the Python binding (pybind11) of the pipeline call and its main stages.
// The package python/normalflow wraps it (keyword arguments, JSON reports as dicts); see its docstrings.
//
// - Meshes cross as normalflow::Mesh objects whose arrays are numpy views of the C++ vectors (no copy out;
//   one copy in, to float32 / uint32).
// - The pipeline's keyword arguments are the library's options table (pipeline/options.h), as the tool's
//   flags are: the same names (with '_'), defaults, checks and results; an error says what is wrong in
//   Python's terms (ValueError: mode 'bilaterl' is not one of bilateral, guided, ...).
// - Long calls release the GIL; the progress callback and the Ctrl-C check run on the calling thread with it
//   held: a pending KeyboardInterrupt (or an exception from the callback) stops the run at its next check
//   and is raised from the call.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/errors.h"
#include "core/mesh.h"
#include "core/mesh_report.h"
#include "core/version.h"
#include "io/io.h"
#include "io/util/report_json.h"
#include "metrics/compare.h"
#include "metrics/compare_report.h"
#include "metrics/noise.h"
#include "pipeline/options.h"
#include "pipeline/pipeline.h"
#include "pipeline/report_json.h"
#include "sdf/image_to_volume.h"
#ifdef NORMALFLOW_HAS_CGAL
#include "io/cgal/repair.h"
#endif
#ifdef NORMALFLOW_HAS_OPENMESH
#include "io/openmesh/smoothing.h"
#endif

namespace py = pybind11;
using namespace normalflow;

namespace {

static_assert(sizeof(Vec3f) == 3 * sizeof(float) && sizeof(Tri) == 3 * sizeof(std::uint32_t) && sizeof(Rgba8) == 4 &&
              sizeof(TexCoord) == 2 * sizeof(float));

/// A numpy view (rows × C) of a vector of C-element records, kept alive by owner.
template <class Scalar, int C, class Record>
py::object view(std::vector<Record>& v, py::handle owner) {
    if (v.empty() && C != 3) return py::none();
    const auto rows = static_cast<py::ssize_t>(v.size());
    return py::array_t<Scalar>({rows, py::ssize_t(C)}, {py::ssize_t(sizeof(Record)), py::ssize_t(sizeof(Scalar))},
                               reinterpret_cast<Scalar*>(v.data()), owner);
}

/// Copies an (n × C) array into a vector of C-element records; `what` names it in the error.
template <class Scalar, int C, class Record>
std::vector<Record> records(const py::array_t<Scalar, py::array::c_style | py::array::forcecast>& a, const char* what) {
    if (a.ndim() != 2 || a.shape(1) != C)
        throw InvalidInput(std::string(what) + ": expected an array of shape (n, " + std::to_string(C) + "), got " +
                           std::to_string(a.ndim()) + " dimensions" +
                           (a.ndim() == 2
                                ? " of shape (" + std::to_string(a.shape(0)) + ", " + std::to_string(a.shape(1)) + ")"
                                : ""));
    std::vector<Record> out(static_cast<std::size_t>(a.shape(0)));
    if (!out.empty()) std::memcpy(static_cast<void*>(out.data()), a.data(), out.size() * sizeof(Record));
    return out;
}

Mesh make_mesh(const py::array_t<float, py::array::c_style | py::array::forcecast>& vertices,
               const py::object& face_object,
               const std::optional<py::array_t<float, py::array::c_style | py::array::forcecast>>& normals,
               const std::optional<py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>>& colors,
               const std::optional<py::array_t<float, py::array::c_style | py::array::forcecast>>& texcoords) {
    Mesh m;
    m.positions = records<float, 3, Vec3f>(vertices, "vertices");
    const py::array face_array = py::array::ensure(face_object);  // a list of lists too, as numpy reads it
    if (!face_array) throw InvalidInput("faces: expected an array of shape (m, 3) of vertex indices");
    const char kind = face_array.dtype().kind();
    if (kind != 'i' && kind != 'u' && face_array.size() > 0)
        throw InvalidInput("faces: expected integer vertex indices, got an array of " +
                           std::string(py::str(face_array.dtype())));
    const auto faces = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(face_array);
    if (faces.ndim() != 2 || faces.shape(1) != 3)
        throw InvalidInput("faces: expected an array of shape (m, 3) of vertex indices");
    const std::int64_t* f = faces.data();
    const auto n = static_cast<std::int64_t>(m.positions.size());
    m.triangles.resize(static_cast<std::size_t>(faces.shape(0)));
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (int c = 0; c < 3; ++c) {
            const std::int64_t i = f[3 * t + c];
            if (i < 0 || i >= n)
                throw InvalidInput("faces: row " + std::to_string(t) + " has index " + std::to_string(i) +
                                   ", outside the " + std::to_string(n) + " vertices");
            m.triangles[t][c] = static_cast<std::uint32_t>(i);
        }
    const auto per_vertex = [&](std::size_t size, const char* what) {
        if (size != m.positions.size())
            throw InvalidInput(std::string(what) + ": " + std::to_string(size) + " rows for " +
                               std::to_string(m.positions.size()) + " vertices");
    };
    if (normals) per_vertex((m.normals = records<float, 3, Vec3f>(*normals, "normals")).size(), "normals");
    if (colors) per_vertex((m.colors = records<std::uint8_t, 4, Rgba8>(*colors, "colors")).size(), "colors");
    if (texcoords) per_vertex((m.texcoords = records<float, 2, TexCoord>(*texcoords, "texcoords")).size(), "texcoords");
    return m;
}

/// A volume with what read_volume found (the file's spacing sets a volume input's length unit, as in the tool).
struct PyVolume {
    Volume volume;
    VolumeReadInfo info;  ///< spacing 0 when the volume came from a mesh
};

/// Progress into a Python callable, and Ctrl-C: see the file comment.
class PyProgress : public Progress {
public:
    explicit PyProgress(py::object callback) : callback_(std::move(callback)), owner_(std::this_thread::get_id()) {}

    void begin(std::string_view stage) override {
        stage_ = std::string(stage);
        last_ = -1;
        call(0.0);
    }
    void progress(double fraction) override {
        if (fraction - last_ >= 0.01 || fraction >= 1.0) call(fraction);
    }
    bool should_stop() override {
        if (error_) return true;
        if (std::this_thread::get_id() != owner_) return false;
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) error_.emplace();  // takes the pending exception (KeyboardInterrupt)
        return error_.has_value();
    }
    /// Raises what stopped the run (the GIL held); nothing when the run was not stopped by Python.
    void raise_pending() {
        if (error_) {
            py::error_already_set e = std::move(*error_);
            error_.reset();
            throw e;
        }
    }

private:
    void call(double fraction) {
        last_ = fraction;
        if (callback_.is_none() || error_ || std::this_thread::get_id() != owner_) return;
        py::gil_scoped_acquire gil;
        try {
            callback_(stage_, fraction);
        } catch (py::error_already_set& e) {
            error_.emplace(std::move(e));
        }
    }

    py::object callback_;
    std::thread::id owner_;
    std::string stage_;
    double last_ = -1;
    std::optional<py::error_already_set> error_;
};

/// Runs f without the GIL; what the progress callback or Ctrl-C raised is raised from here.
template <class F>
auto released(PyProgress& progress, F&& f) {
    try {
        auto result = [&] {
            py::gil_scoped_release release;
            return f();
        }();
        progress.raise_pending();
        return result;
    } catch (const Cancelled&) {
        progress.raise_pending();
        throw;
    }
}

Command command_of(const std::string& name) {
    for (Command c : {Command::Smooth, Command::Remesh, Command::Voxelize, Command::Extract})
        if (name == to_string(c)) return c;
    throw InvalidInput("no command " + name + " (smooth, remesh, voxelize, extract)");
}

/// The keyword arguments of a call of command c as its options: each a row of the table (below the Library tier),
/// its value checked as the tool checks a flag's. None leaves an option at its default.
RunOptions run_options(Command c, const py::dict& keywords) {
    RunOptions o = default_options(c);
    for (const auto& [k, value] : keywords) {
        const std::string key = py::str(k);
        const OptionSpec* spec = nullptr;
        for (const OptionSpec* s : user_options(c))
            if (s->key() == key) spec = s;
        if (!spec)
            throw py::type_error(std::string(to_string(c)) + "() got an unexpected keyword argument '" + key + "'");
        if (value.is_none()) continue;
        const bool is_bool = py::isinstance<py::bool_>(value);
        if (is_bool != (spec->kind == OptionKind::Switch))
            throw py::type_error(key + ": expected " + (is_bool ? option_range(*spec) : "True or False") + ", got " +
                                 std::string(py::str(py::type::of(value).attr("__name__"))));
        std::string text;
        if (is_bool)
            text = value.cast<bool>() ? "true" : "false";
        else if (py::isinstance<py::str>(value))
            text = value.cast<std::string>();
        else if (py::isinstance<py::int_>(value))
            text = py::str(value);
        else if (PyFloat_Check(value.ptr()) || py::hasattr(value, "__float__"))
            text = py::repr(py::float_(py::reinterpret_borrow<py::object>(value)));
        else
            throw py::type_error(key + ": expected " + option_range(*spec) + ", got " +
                                 std::string(py::str(py::type::of(value).attr("__name__"))));
        try {
            set_option(*spec, o, text);
        } catch (const InvalidInput& e) {
            throw InvalidInput(key + " " + e.what());
        }
    }
    return o;
}

/// The keyword arguments of command c, one per line: name=default, what it takes, its help; by group.
std::string keyword_help(Command c) {
    const RunOptions defaults = default_options(c);
    std::string out;
    int group = -1;
    for (const OptionSpec* s : user_options(c)) {
        if (int(s->group) != group) {
            group = int(s->group);
            out += std::string(out.empty() ? "" : "\n") + to_string(s->group) + ":\n";
        }
        const std::string value = option_text(*s, defaults);
        out += "    " + s->key() + "=" +
               (s->kind == OptionKind::Switch ? (value == "true" ? "True" : "False")
                : value.empty()               ? "None"
                : s->kind == OptionKind::Choice || !s->zero.empty() || s->kind == OptionKind::Bytes ? "'" + value + "'"
                                                                                                    : value) +
               ": " + s->help + " (" + option_range(*s) + ")\n";
    }
    return out;
}

py::tuple mesh_and_report(Mesh&& m, const Json& j) { return py::make_tuple(py::cast(std::move(m)), j.dump()); }

std::string_view bytes_view(const py::bytes& b) {
    return {PyBytes_AS_STRING(b.ptr()), std::size_t(PyBytes_GET_SIZE(b.ptr()))};
}

/// A Python runner(context, count, make, take) (normalflow's _DaskBricks) as the pipeline's BrickMessageRunner: it is
/// called with the GIL, make and take run the C++ side without it.
BrickMessageRunner brick_runner(const py::object& runner) {
    if (runner.is_none()) return {};
    return [runner](const std::string& context, int count, const std::function<std::string(int)>& make,
                    const std::function<void(const std::string&)>& take) {
        py::gil_scoped_acquire gil;
        const py::cpp_function py_make([&make](int i) {
            std::string job;
            {
                py::gil_scoped_release release;
                job = make(i);
            }
            return py::bytes(job);
        });
        const py::cpp_function py_take([&take](const py::bytes& outcome) {
            const std::string message(bytes_view(outcome));
            py::gil_scoped_release release;
            take(message);
        });
        runner(py::bytes(context), count, py_make, py_take);
    };
}

}  // namespace

PYBIND11_MODULE(_normalflow, m) {
    m.doc() =
        "normalflow: geometric surface processing via normal maps (Tasdizen et al. 2003); see the normalflow package";
    m.attr("__version__") = version();

    static py::exception<InvalidInput> invalid(m, "InvalidInput", PyExc_ValueError);
    static py::exception<IoError> io_error(m, "IoError", PyExc_OSError);
    static py::exception<NumericalError> numerical(m, "NumericalError", PyExc_ArithmeticError);
    static py::exception<OutOfMemory> oom(m, "OutOfMemory", PyExc_MemoryError);
    static py::exception<Cancelled> cancelled(m, "Cancelled", PyExc_RuntimeError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InvalidInput& e) {
            invalid(e.what());
        } catch (const IoError& e) {
            io_error(e.what());
        } catch (const NumericalError& e) {
            numerical(e.what());
        } catch (const OutOfMemory& e) {
            oom(e.what());
        } catch (const Cancelled& e) {
            cancelled(e.what());
        }
    });

    py::class_<Mesh>(m, "Mesh", "A triangle mesh; its arrays are numpy views of the mesh's own storage")
        .def(py::init(&make_mesh), py::arg("vertices"), py::arg("faces"), py::arg("normals") = py::none(),
             py::arg("colors") = py::none(), py::arg("texcoords") = py::none(),
             "vertices (n, 3) and faces (m, 3) of indices into them; optional per-vertex normals (n, 3), "
             "RGBA colors (n, 4) uint8 and texcoords (n, 2)")
        .def_property_readonly(
            "vertices", [](py::object self) { return view<float, 3>(self.cast<Mesh&>().positions, self); },
            "(n, 3) float32")
        .def_property_readonly(
            "faces", [](py::object self) { return view<std::uint32_t, 3>(self.cast<Mesh&>().triangles, self); },
            "(m, 3) uint32")
        .def_property_readonly(
            "normals",
            [](py::object self) -> py::object {
                Mesh& mesh = self.cast<Mesh&>();
                return mesh.normals.empty() ? py::none() : view<float, 3>(mesh.normals, self);
            },
            "(n, 3) float32 unit vertex normals, or None")
        .def_property_readonly(
            "colors", [](py::object self) { return view<std::uint8_t, 4>(self.cast<Mesh&>().colors, self); },
            "(n, 4) uint8 RGBA, or None")
        .def_property_readonly(
            "texcoords", [](py::object self) { return view<float, 2>(self.cast<Mesh&>().texcoords, self); },
            "(n, 2) float32, or None")
        .def("_report_json", [](const Mesh& mesh) { return to_json(mesh_report(mesh)).dump(); })
        .def("__repr__", [](const Mesh& mesh) {
            return "<normalflow.Mesh " + std::to_string(mesh.positions.size()) + " vertices, " +
                   std::to_string(mesh.triangles.size()) + " triangles>";
        });

    py::class_<PyVolume>(m, "Volume", "A narrow-band signed distance volume, negative inside")
        .def_property_readonly("dims", [](const PyVolume& v) { return v.volume.grid.dims; })
        .def_property_readonly("voxel_size", [](const PyVolume& v) { return v.volume.grid.voxel_size; })
        .def_property_readonly("origin",
                               [](const PyVolume& v) {
                                   const Vec3d& o = v.volume.grid.origin;
                                   return std::array<double, 3>{o.x, o.y, o.z};
                               })
        .def_property_readonly("half_width", [](const PyVolume& v) { return v.volume.half_width; })
        .def_property_readonly("blocks", [](const PyVolume& v) { return v.volume.block_count(); })
        .def(
            "to_dense",
            [](const PyVolume& v) {
                const Grid& g = v.volume.grid;
                py::array_t<float> out({g.dims[0], g.dims[1], g.dims[2]});
                auto a = out.mutable_unchecked<3>();
                for (int i = 0; i < g.dims[0]; ++i)
                    for (int j = 0; j < g.dims[1]; ++j)
                        for (int k = 0; k < g.dims[2]; ++k) a(i, j, k) = v.volume.value(i, j, k);
                return out;
            },
            "The samples as a dense (nx, ny, nz) float32 array indexed [i, j, k], ± the band's width outside it")
        .def(
            "write",
            [](const PyVolume& v, const std::filesystem::path& path) {
                py::gil_scoped_release release;
                write_volume(path.string(), v.volume);
            },
            py::arg("path"), "Writes .vdb or .nrrd (written whole or not at all)")
        .def("__repr__", [](const PyVolume& v) {
            const Grid& g = v.volume.grid;
            return "<normalflow.Volume " + std::to_string(g.dims[0]) + "x" + std::to_string(g.dims[1]) + "x" +
                   std::to_string(g.dims[2]) + ", voxel " + std::to_string(g.voxel_size) + ", " +
                   std::to_string(v.volume.block_count()) + " blocks>";
        });

    m.def(
        "read_mesh",
        [](const std::string& path) {
            py::gil_scoped_release release;
            return read_mesh(path);
        },
        py::arg("path"));
    m.def(
        "write_mesh",
        [](const std::string& path, const Mesh& mesh) {
            py::gil_scoped_release release;
            write_mesh(path, mesh);
        },
        py::arg("path"), py::arg("mesh"));
    m.def(
        "read_volume",
        [](const std::string& path, std::optional<double> iso, std::optional<double> label, bool negate,
           double voxel_size) {
            VolumeInput in;
            in.iso = iso;
            in.label = label;
            in.negate = negate;
            in.voxel_size = voxel_size;
            py::gil_scoped_release release;
            PyVolume v;
            v.volume = read_volume(path, in, &v.info);
            return v;
        },
        py::arg("path"), py::arg("iso") = py::none(), py::arg("label") = py::none(), py::arg("negate") = false,
        py::arg("voxel_size") = 0.0);
    m.def(
        "image_to_volume",
        [](const py::array_t<float, py::array::c_style | py::array::forcecast>& values, std::array<double, 3> spacing,
           std::array<double, 3> origin, std::optional<double> iso, std::optional<double> label, bool negate,
           double voxel_size) {
            if (values.ndim() != 3) throw InvalidInput("image: expected a 3-dimensional array indexed [i, j, k]");
            ScalarImage image;
            for (int a = 0; a < 3; ++a) image.dims[a] = static_cast<int>(values.shape(a));
            image.values.resize(image.sample_count());
            // numpy's [i, j, k] (k fastest) into the image's x-fastest order
            auto v = values.unchecked<3>();
            for (int k = 0; k < image.dims[2]; ++k)
                for (int j = 0; j < image.dims[1]; ++j)
                    for (int i = 0; i < image.dims[0]; ++i)
                        image.values[std::size_t(i) +
                                     std::size_t(image.dims[0]) * (std::size_t(j) + std::size_t(image.dims[1]) * k)] =
                            v(i, j, k);
            image.origin = Vec3d(origin[0], origin[1], origin[2]);
            for (int a = 0; a < 3; ++a) {
                image.axes[a] = Vec3d(0, 0, 0);
                (a == 0 ? image.axes[a].x : a == 1 ? image.axes[a].y : image.axes[a].z) = spacing[a];
            }
            ImageToVolumeOptions o;
            if (iso && label) throw InvalidInput("image: iso and label are exclusive");
            if (label) {
                o.surface.label = label;
            } else if (iso) {
                o.surface.iso = *iso;
            } else {
                const std::optional<double> mask = binary_mask_label(image);
                if (!mask)
                    throw InvalidInput("image: not a binary mask; give iso= (a scalar image) or label= (a label map)");
                o.surface.label = mask;
            }
            o.surface.negate = negate;
            o.voxel_size = voxel_size;
            py::gil_scoped_release release;
            PyVolume out{image_to_volume(image, o), {}};
            out.info.spacing = spacing;
            return out;
        },
        py::arg("values"), py::arg("spacing"), py::arg("origin"), py::arg("iso") = py::none(),
        py::arg("label") = py::none(), py::arg("negate") = false, py::arg("voxel_size") = 0.0);

    m.def(
        "keywords",
        [](const std::string& command) {
            std::vector<std::string> names;
            for (const OptionSpec* s : user_options(command_of(command))) names.push_back(s->key());
            return names;
        },
        py::arg("command"), "The keyword arguments of smooth, remesh, voxelize or extract");
    m.def(
        "keyword_help", [](const std::string& command) { return keyword_help(command_of(command)); },
        py::arg("command"), "The keyword arguments of a command with their defaults, ranges and help, by group");

    m.def(
        "smooth",
        [](const Mesh& mesh, const py::dict& keywords, py::object callback, py::object bricks) {
            const RunOptions run = run_options(Command::Smooth, keywords);
            const PipelineOptions opt = pipeline_options(run, Command::Smooth);
            PyProgress progress(std::move(callback));
            const BrickMessageRunner runner = brick_runner(bricks);
            PipelineResult r = released(progress, [&] {
                validate(opt);
                return smooth_mesh(mesh, opt, &progress, runner ? &runner : nullptr);
            });
            return mesh_and_report(std::move(r.mesh), run_report_json(Command::Smooth, run, r.report));
        },
        py::arg("mesh"), py::arg("keywords"), py::arg("progress"), py::arg("bricks") = py::none());

    py::class_<BrickWorker>(m, "BrickWorker",
                            "What a worker of a bricked run does with its bricks: built from the run's context "
                            "message, run(job) returns the brick's outcome (both bytes)")
        .def(py::init([](const py::bytes& context) { return std::make_unique<BrickWorker>(bytes_view(context)); }),
             py::arg("context"))
        .def(
            "run",
            [](const BrickWorker& w, const py::bytes& job) {
                const std::string_view message = bytes_view(job);
                std::string outcome;
                {
                    py::gil_scoped_release release;
                    outcome = w.run(message);
                }
                return py::bytes(outcome);
            },
            py::arg("job"));

    m.def(
        "smooth_volume",
        [](const PyVolume& in, const py::dict& keywords, py::object callback, bool want_mesh) {
            const RunOptions run = run_options(Command::Smooth, keywords);
            PipelineOptions opt = pipeline_options(run, Command::Smooth);
            if (volume_input(run).voxel_size != 0)
                throw InvalidInput(
                    "a Volume keeps its grid: resample it with read_volume's or image_to_volume's "
                    "voxel_size");
            if (in.info.spacing[0] > 0) set_volume_length_scale(opt, in.info);  // as the tool: the file's spacing
            PyProgress progress(std::move(callback));
            PyVolume out{in.volume, in.info};
            PipelineResult r =
                released(progress, [&] { return smooth_volume_input(out.volume, opt, &progress, want_mesh); });
            Json j = to_json(r.report);
            j.set("mode", to_string(opt.smooth.mode));
            set_parameters(j, run, Command::Smooth, opt, r.report, in.volume.grid.voxel_size, false);
            j.set("version", version());
            if (!want_mesh) return py::make_tuple(py::cast(std::move(out)), j.dump());
            return mesh_and_report(std::move(r.mesh), j);
        },
        py::arg("volume"), py::arg("keywords"), py::arg("progress"), py::arg("want_mesh"));

    m.def(
        "remesh",
        [](const Mesh& mesh, const py::dict& keywords, py::object callback, py::object bricks) {
            const RunOptions run = run_options(Command::Remesh, keywords);
            const PipelineOptions opt = pipeline_options(run, Command::Remesh);
            PyProgress progress(std::move(callback));
            const BrickMessageRunner runner = brick_runner(bricks);
            PipelineResult r = released(progress, [&] {
                validate(opt);
                return smooth_mesh(mesh, opt, &progress, runner ? &runner : nullptr);
            });
            return mesh_and_report(std::move(r.mesh), run_report_json(Command::Remesh, run, r.report));
        },
        py::arg("mesh"), py::arg("keywords"), py::arg("progress"), py::arg("bricks") = py::none());

    m.def(
        "voxelize",
        [](const Mesh& mesh, const py::dict& keywords, py::object callback) {
            const RunOptions run = run_options(Command::Voxelize, keywords);
            const PipelineOptions opt = pipeline_options(run, Command::Voxelize);
            PyProgress progress(std::move(callback));
            PipelineReport r;
            PyVolume v{released(progress, [&] { return mesh_to_volume(mesh, opt, &r, &progress); }), {}};
            return py::make_tuple(py::cast(std::move(v)), run_report_json(Command::Voxelize, run, r).dump());
        },
        py::arg("mesh"), py::arg("keywords"), py::arg("progress"));

    m.def(
        "extract",
        [](const PyVolume& v, const py::dict& keywords, py::object callback) {
            const RunOptions run = run_options(Command::Extract, keywords);
            const PipelineOptions opt = pipeline_options(run, Command::Extract);
            if (volume_input(run).voxel_size != 0)
                throw InvalidInput(
                    "a Volume keeps its grid: resample it with read_volume's or image_to_volume's "
                    "voxel_size");
            PyProgress progress(std::move(callback));
            PipelineReport r;
            Mesh out = released(progress, [&] { return volume_to_mesh(v.volume, opt, &r, &progress); });
            Json j = Json::object();
            j.set("extract", to_json(r.extract));
            if (r.decimated) j.set("decimate", to_json(r.decimate));
            set_parameters(j, run, Command::Extract, opt, r, v.volume.grid.voxel_size, false);
            j.set("warnings", Json::array(r.warnings)).set("version", version());
            return mesh_and_report(std::move(out), j);
        },
        py::arg("volume"), py::arg("keywords"), py::arg("progress"));

    m.def(
        "compare",
        [](const Mesh& reference, const Mesh& candidate, std::size_t samples, std::uint64_t seed, double crease_angle,
           double crease_radius, bool correspondence, bool self_intersections) {
            CompareReport report;
            report.reference = "reference";
            report.options.sampling.samples = samples;
            report.options.sampling.seed = seed;
            report.options.crease.angle_deg = crease_angle;
            report.options.crease.radius_relative = crease_radius;
            report.options.correspondence = correspondence;
            {
                py::gil_scoped_release release;
                CompareReportRow row;
                row.name = "candidate";
                if (correspondence) {
                    const std::string mismatch = correspondence_mismatch(candidate, reference);
                    if (!mismatch.empty()) throw InvalidInput("correspondence: " + mismatch);
                }
                row.comparison = compare_meshes(candidate, reference, report.options);
#ifdef NORMALFLOW_HAS_CGAL
                if (self_intersections)
                    row.self_intersections = static_cast<long long>(count_self_intersections(candidate));
#else
                (void)self_intersections;
#endif
                report.rows.push_back(std::move(row));
            }
            return to_json(report).dump();
        },
        py::arg("reference"), py::arg("candidate"), py::arg("samples"), py::arg("seed"), py::arg("crease_angle"),
        py::arg("crease_radius"), py::arg("correspondence"), py::arg("self_intersections"));
    {
        const CompareOptions d;
        m.attr("COMPARE_DEFAULTS") =
            py::dict(py::arg("samples") = d.sampling.samples, py::arg("seed") = d.sampling.seed,
                     py::arg("crease_angle") = d.crease.angle_deg, py::arg("crease_radius") = d.crease.radius_relative);
    }

    m.def(
        "noise",
        [](const Mesh& mesh, double sigma, std::uint64_t seed, const std::string& kind, const std::string& direction,
           double fraction) {
            NoiseOptions o;
            o.sigma = sigma;
            o.seed = seed;
            if (kind != "gaussian" && kind != "impulsive")
                throw InvalidInput("kind: expected gaussian or impulsive, got " + kind);
            if (direction != "normal" && direction != "random")
                throw InvalidInput("direction: expected normal or random, got " + direction);
            o.kind = kind == "gaussian" ? NoiseKind::Gaussian : NoiseKind::Impulsive;
            o.direction = direction == "normal" ? NoiseDirection::Normal : NoiseDirection::Random;
            o.impulsive_fraction = fraction;
            Mesh out = mesh;
            NoiseReport r;
            {
                py::gil_scoped_release release;
                r = add_noise(out, o);
            }
            Json j = Json::object();
            j.set("sigma", o.sigma)
                .set("seed", static_cast<unsigned long long>(o.seed))
                .set("kind", kind)
                .set("direction", direction);
            j.set("mean_edge_length", r.mean_edge_length).set("sigma_world", r.sigma_world);
            j.set("vertices", r.vertices).set("displaced", r.displaced).set("rms_displacement", r.rms_displacement);
            return mesh_and_report(std::move(out), j);
        },
        py::arg("mesh"), py::arg("sigma"), py::arg("seed"), py::arg("kind"), py::arg("direction"), py::arg("fraction"));
    {
        const NoiseOptions d;
        m.attr("NOISE_DEFAULTS") =
            py::dict(py::arg("sigma") = d.sigma, py::arg("seed") = d.seed, py::arg("fraction") = d.impulsive_fraction);
    }

#ifdef NORMALFLOW_HAS_OPENMESH
    m.def(
        "taubin",
        [](const Mesh& mesh, int iterations, double lambda, double mu, bool fix_boundary, py::object callback) {
            TaubinOptions o;
            o.iterations = iterations;
            o.lambda = lambda;
            o.mu = mu;
            o.fix_boundary = fix_boundary;
            Mesh out = mesh;
            PyProgress progress(std::move(callback));
            const SmoothingReport r = released(progress, [&] { return taubin_smooth(out, o, &progress); });
            Json j = Json::object();
            j.set("vertices", r.vertices).set("triangles", out.triangles.size()).set("faces_skipped", r.faces_skipped);
            j.set("boundary_vertices", r.boundary_vertices).set("iterations", r.iterations);
            j.set("max_displacement", r.max_displacement).set("warnings", Json::array(r.warnings));
            return mesh_and_report(std::move(out), j);
        },
        py::arg("mesh"), py::arg("iterations"), py::arg("lambda_"), py::arg("mu"), py::arg("fix_boundary"),
        py::arg("progress"));
    {
        const TaubinOptions d;
        m.attr("TAUBIN_DEFAULTS") =
            py::dict(py::arg("iterations") = d.iterations, py::arg("lambda_") = d.lambda, py::arg("mu") = d.mu);
    }
#endif
}
