#pragma once
/// \file nrrd.h
/// Reading and writing 3-D scalar volumes as NRRD files (http://teem.sourceforge.net/nrrd/format.html),
/// converting between the dense NRRD grid and normalflow's sparse narrow-band Volume, and reading a
/// NRRD file whole as a dense ScalarImage (any spacing and orientation).
/// No third-party dependency; gzip encoding is read when the build has zlib.

#include <string>

#include "core/volume.h"
#include "sdf/image_to_volume.h"

namespace normalflow {

/// How a dense scalar field becomes a narrow-band Volume.
struct VolumeReadOptions {
    double iso = 0.0;        ///< file units: the surface is {value == iso}; stored phi = value - iso
    bool negate = false;     ///< true if the field is larger *inside* (e.g. an intensity or a density):
                             ///< stored phi = iso - value, so that phi is negative inside
    float half_width = 0.f;  ///< voxels, > 0: blocks holding a sample with |phi| < half_width * h are
                             ///< stored; 0 = the file's normalflow_half_width key if present, else 3
};

/// Reads a 3-D NRRD file (magic NRRD0001..NRRD0005) into a sparse Volume.
///
/// Accepted: `dimension: 3`; type float, double, (u)char, (u)short, (u)int (all Teem spellings);
/// encoding raw, ascii/text, and gzip when built with zlib; little or big endian; `byte skip`
/// (>= 0, or -1 for raw); `line skip`; an attached header (.nrrd) or a detached one (.nhdr) whose
/// `data file:` names a single file, relative to the header's folder or absolute (line skip, byte skip
/// and the encoding apply to that file). Geometry from `space origin` + `space directions`, or else
/// `spacings` (> 0, + `axis mins`), or else unit spacing at `space origin` (or 0). The voxels must be
/// isotropic (all three steps of equal length to 1e-5 relative):
///   - directions along x, y, z in that order with positive steps: sample (i, j, k) sits at
///     origin + h · (i, j, k), origin = `space origin`, and the placement is the identity;
///   - other orthogonal directions (rotated, permuted, flipped; orthogonal to 1e-5): grid.origin is
///     (0, 0, 0), grid.placement.rotation the unit directions (made orthonormal to rounding, keeping the
///     file's handedness: a reflection for a flipped axis) and grid.placement.translation `space
///     origin`, so that sample (i, j, k) sits in the world at placement.point(h · (i, j, k)).
/// Space coordinates are taken as written (no conversion between LPS and RAS spaces).
/// Anisotropic or non-orthogonal files are refused here: read them with read_nrrd_image.
///
/// Conversion: phi = value - iso (or iso - value with negate). Every 8^3 block that contains a
/// sample with |phi| < half_width * h, or samples of both signs, is stored with its exact values;
/// every other block becomes a tile, inside (-background) if its samples are negative, outside
/// otherwise. background = half_width * h unless the file carries `normalflow_background:=`
/// (as written by write_nrrd). The dense grid is streamed 8 z-slices at a time, never held whole.
///
/// \throw IoError if the file (or its data file) cannot be opened or read; InvalidInput
///        ("read_nrrd: path: ...", naming the header file) for bad contents: not NRRD, missing or
///        malformed fields, dimension != 3, unsupported type or encoding, `data file: LIST` or a
///        format-string list of data files, anisotropic or non-orthogonal axes, non-positive spacings,
///        sizes that claim more data than the file holds (checked before allocating), truncated or
///        corrupt data, NaN/Inf samples, and options out of range. The volume read passes Volume::check.
/// Cost: O(#samples) time, memory O(stored blocks + one 8-slice slab). Single-threaded.
Volume read_nrrd(const std::string& path, const VolumeReadOptions& opt);

/// read_nrrd with default options: the file holds signed distances, negative inside.
Volume read_nrrd(const std::string& path);

/// Reads a 3-D NRRD file whole into a dense ScalarImage: the same files as read_nrrd (attached or
/// detached header, every type, encoding and skip), but any spacing and orientation: axes[a] is the
/// a-th `space directions` vector as written (anisotropic, rotated, flipped, not necessarily
/// orthogonal: check_image refuses those later), or `spacings` along x, y, z (non-zero; negative
/// flips), or unit steps; origin is `space origin`, else `axis mins` (with spacings), else 0.
/// Space coordinates are taken as written (no LPS/RAS conversion); centerings are ignored.
/// Values are the file's samples as floats (no iso, no negation).
/// The result holds dims >= 1, values.size() == dims product, finite values, origin and axes, and
/// axes of non-zero length.
/// \throw IoError if the file or its data file cannot be opened or read; InvalidInput
///        ("read_nrrd_image: path: ...") for bad contents as read_nrrd (except the spacing and
///        orientation rules); OutOfMemory if the samples (4 bytes each) cannot be allocated.
/// Cost: O(#samples) time; memory: the image (4 bytes a sample) and a 1 MiB buffer. Single-threaded.
ScalarImage read_nrrd_image(const std::string& path);

/// Writes v as a dense NRRD0004 file: float, raw, native endianness, `space dimension: 3`, and the
/// keys `normalflow_half_width:=` and `normalflow_background:=`. The geometry is the world's: `space
/// directions` = h · the columns of v.grid.placement.rotation and `space origin` =
/// placement.point(grid.origin), so an identity placement writes (h,0,0) (0,h,0) (0,0,h) and
/// grid.origin. read_nrrd restores v: exactly with the identity placement; a placed volume (rotated
/// or flipped) reads back with grid.origin (0, 0, 0) and the whole offset in placement.translation
/// (the same world positions, to rounding). Samples in stored blocks are written
/// as they are, others as +background (outside tiles) or -background (inside tiles).
/// Written atomically (temporary file + rename), streaming one z-slice at a time.
/// \throw InvalidInput (Volume::check) if v breaks its invariants (empty grid, non-positive voxel
///        size, inconsistent blocks, ...); NumericalError for a NaN/Inf sample; IoError if the file
///        cannot be written.
/// Cost: O(#samples) time and file size (4 bytes per sample). Single-threaded.
void write_nrrd(const std::string& path, const Volume& v);

}  // namespace normalflow
