#pragma once
/// The exported model artifact: one self-describing HDF5 file (schema: docs/artifact_schema.md).
///   /            attrs kind = "foresight.artifact", format_version, model_type, seed
///   /config      resolved YAML config (string)
///   /model       model-type specific attributes and tensors
///   /normalisation, /weights/<module path>/{weight,bias}

#include <cstdint>
#include <string>

#include "core/h5.h"

namespace foresight {

inline constexpr const char* kArtifactKind = "foresight.artifact";
inline constexpr std::int64_t kArtifactFormatVersion = 1;

class Artifact {
 public:
  /// Opens and checks kind, format version and model type. A missing, truncated, foreign or
  /// wrong-type file is an Error naming the file and what was found.
  static Artifact Open(const std::string& path, const std::string& expected_model_type);

  const h5::File& file() const { return file_; }
  const std::string& model_type() const { return model_type_; }
  const std::string& config_yaml() const { return config_yaml_; }
  std::int64_t seed() const { return seed_; }

  /// An integer attribute of `object` in [lo, hi] (an Error naming the file, the attribute and the
  /// value otherwise: a loader never narrows an out-of-range int64 silently).
  int IntAttr(const std::string& object, const std::string& name, int lo, int hi) const;
  /// A finite floating-point attribute in [lo, hi] (likewise).
  double DoubleAttr(const std::string& object, const std::string& name, double lo, double hi) const;

  /// Writes the common header of a new artifact.
  static void WriteHeader(h5::File* file, const std::string& model_type,
                          const std::string& config_yaml, std::int64_t seed);

 private:
  explicit Artifact(h5::File f) : file_(std::move(f)) {}
  h5::File file_;
  std::string model_type_, config_yaml_;
  std::int64_t seed_ = 0;
};

}  // namespace foresight
