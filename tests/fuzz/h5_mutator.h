#pragma once
/// Structure-aware edits of a valid HDF5 file for the artifact fuzz targets
/// (tests/fuzz/artifact_*): what a hostile user can do to an exported artifact with h5py, chosen by
/// the fuzz input. Generic: it knows no artifact schema, only the datasets and attributes it finds
/// in the file.
///
/// Edits (1 to 4 per input, each chosen by one byte):
///   - set a numeric attribute (any integer or float type; a scalar or one element of an array) to
///     ByteReader::Double(), possibly re-typed as float64 (integer attributes: the value is
///     converted with saturation, NaN -> 0, as h5py would refuse nothing else);
///   - set a string attribute to a short string from the bytes, to another string attribute's value
///     or to its own value with one character changed;
///   - delete an attribute; delete a dataset;
///   - replace a dataset by one of other dims (rank 1 or 2, dims 0, 1, original +- 1 or small),
///     filled from the bytes and then from the original values;
///   - set one element of a numeric dataset to Double();
///   - change a numeric dataset's element type (float64 / float32 / int64 / uint8).

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

namespace foresight::fuzz {

/// Applies the edits read from `in` to the HDF5 file `path` in place. Edits that do not apply (no
/// such object in the file, an HDF5 refusal) are skipped; the file stays a readable HDF5 file.
void MutateH5(const std::string& path, ByteReader* in);

/// The bytes of `path` (aborts when it cannot be read: the targets' base artifacts must exist).
std::vector<std::uint8_t> ReadFileBytes(const std::string& path);

/// A finding when a model that loaded answers a finite query with non-finite values: aborts.
inline void ExpectFiniteAnswer(bool finite, const std::string& path, const char* what) {
  if (!finite) {
    std::fprintf(stderr, "fuzz: %s accepted but %s is not finite (silently wrong output)\n",
                 path.c_str(), what);
    std::abort();
  }
}

}  // namespace foresight::fuzz
