#pragma once
/// \file nifti.h
/// Reading 3-D scalar images from NIfTI-1 and NIfTI-2 files (.nii, .nii.gz), the volume format of
/// neuroimaging (https://nifti.nimh.nih.gov/nifti-1/, https://nifti.nimh.nih.gov/nifti-2/).
/// No third-party dependency; .nii.gz is read when the build has zlib.

#include <string>

#include "sdf/image_to_volume.h"

namespace normalflow {

/// Reads a NIfTI-1 (348-byte header, magic "n+1") or NIfTI-2 (540-byte header, magic "n+2") single
/// file into a dense ScalarImage. Compressed files (gzip, recognised by their first two bytes, whatever
/// the name) are read when built with zlib.
///
/// Accepted: either byte order (told by sizeof_hdr); `dim[0]` 3, or 4..7 with every dimension beyond
/// the third equal to 1; datatypes uint8, int8, int16, uint16, int32, uint32, int64, uint64, float32,
/// float64. Header extensions between the header and `vox_offset` are skipped. `bitpix` is not used
/// (the datatype says the sample size).
///
/// Values: value = scl_slope · raw + scl_inter when scl_slope is finite and non-zero, else the raw
/// value; stored as float.
///
/// Geometry, as the standard orders its three methods: sform_code > 0: world = S · (i, j, k, 1) with S
/// the rows srow_x, srow_y, srow_z, so axes[a] is column a of S's 3×3 part and origin its fourth
/// column (the axes need not be orthogonal: check_image refuses those later). Else qform_code > 0: the
/// rotation R of the quaternion (b, c, d, a = sqrt(1 − b² − c² − d²), normalised as nifti1_io does
/// when b² + c² + d² > 1), axes[a] = R column a · pixdim[a+1], axes[2] negated when pixdim[0] (qfac)
/// is negative, origin = qoffset. Else: axes = |pixdim[1..3]| along x, y, z at origin 0.
/// Units (xyzt_units) are ignored: world units are the file's numbers (millimetres in most files).
///
/// The result holds dims >= 1, values.size() == dims product, finite values, origin and axes, and
/// axes of non-zero length (not necessarily orthogonal).
///
/// \throw IoError "read_nifti: path: cannot open (...)" if the file cannot be opened or read;
///        InvalidInput "read_nifti: path: <problem>" for bad contents: not NIfTI (wrong size or magic),
///        .hdr/.img pairs ("ni1"/"ni2"), truncated header or data, a 4-D or larger image, dims < 1,
///        unsupported datatype (named with its code), sizes that claim more data than the file can
///        hold (checked before allocating: the file size for .nii, a deflate ratio of 1100:1 for .gz),
///        vox_offset before the end of the header, non-positive qform spacings, non-finite or zero
///        geometry, a non-finite value (named by its sample index), gzip without zlib.
///        OutOfMemory if the samples (4 bytes each) cannot be allocated.
/// Cost: O(#samples) time; memory: the image (4 bytes a sample) and a 1 MiB buffer. Single-threaded.
ScalarImage read_nifti(const std::string& path);

}  // namespace normalflow
