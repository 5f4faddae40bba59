#pragma once
/// \file nrrd.h
/// Reading and writing 3-D scalar volumes as NRRD files (http://teem.sourceforge.net/nrrd/format.html),
/// converting between the dense NRRD grid and normalflow's sparse narrow-band Volume.
/// No third-party dependency; gzip encoding is read when the build has zlib.

#include <string>

#include "core/volume.h"

namespace normalflow {

/// How a dense scalar field becomes a narrow-band Volume.
struct VolumeReadOptions {
    double iso = 0.0;        ///< file units: the surface is {value == iso}; stored phi = value - iso
    bool negate = false;     ///< true if the field is larger *inside* (e.g. an intensity or a density):
                             ///< stored phi = iso - value, so that phi is negative inside
    float half_width = 0.f;  ///< voxels, > 0: blocks holding a sample with |phi| < half_width * h are
                             ///< stored; 0 = the file's normalflow_half_width key if present, else 3
};

/// Reads a 3-D NRRD file (magic NRRD0001..NRRD0005, attached header) into a sparse Volume.
///
/// Accepted: `dimension: 3`; type float, double, (u)char, (u)short, (u)int (all Teem spellings);
/// encoding raw, ascii/text, and gzip when built with zlib; little or big endian; `byte skip`
/// (>= 0, or -1 for raw); `line skip`; geometry from `space origin` + `space directions` (axis-aligned,
/// positive, in x/y/z order and isotropic to 1e-5 relative), or else `spacings` (+ `axis mins`),
/// or else unit spacing at the origin. Sample (i, j, k) sits at origin + h * (i, j, k).
///
/// Conversion: phi = value - iso (or iso - value with negate). Every 8^3 block that contains a
/// sample with |phi| < half_width * h, or samples of both signs, is stored with its exact values;
/// every other block becomes a tile, inside (-background) if its samples are negative, outside
/// otherwise. background = half_width * h unless the file carries `normalflow_background:=`
/// (as written by write_nrrd). The dense grid is streamed 8 z-slices at a time, never held whole.
///
/// \throw IoError if the file cannot be opened or read; InvalidInput (naming the file) for bad
///        contents: not NRRD, missing or malformed fields, dimension != 3, unsupported type or
///        encoding, detached data files, rotated/anisotropic/negative axes, sizes that claim more
///        data than the file holds (checked before allocating), truncated or corrupt data,
///        NaN/Inf samples, and options out of range. The volume read passes Volume::check.
/// Cost: O(#samples) time, memory O(stored blocks + one 8-slice slab). Single-threaded.
Volume read_nrrd(const std::string& path, const VolumeReadOptions& opt);

/// read_nrrd with default options: the file holds signed distances, negative inside.
Volume read_nrrd(const std::string& path);

/// Writes v as a dense NRRD0004 file: float, raw, native endianness, `space dimension: 3`,
/// `space origin` and `space directions` from v.grid, and the keys `normalflow_half_width:=` and
/// `normalflow_background:=` so read_nrrd restores v exactly. Samples in stored blocks are written
/// as they are, others as +background (outside tiles) or -background (inside tiles).
/// Written atomically (temporary file + rename), streaming one z-slice at a time.
/// \throw InvalidInput (Volume::check) if v breaks its invariants (empty grid, non-positive voxel
///        size, inconsistent blocks, ...); NumericalError for a NaN/Inf sample; IoError if the file
///        cannot be written.
/// Cost: O(#samples) time and file size (4 bytes per sample). Single-threaded.
void write_nrrd(const std::string& path, const Volume& v);

}  // namespace normalflow
