#include "inference/engine/artifact.h"

#include <cmath>

#include "core/error.h"

namespace foresight {

Artifact Artifact::Open(const std::string& path, const std::string& expected_model_type) {
  Artifact a(h5::File::Open(path));
  const h5::File& f = a.file_;
  FS_THROW_UNLESS(f.HasAttr("/", "kind") && f.GetStringAttr("/", "kind") == kArtifactKind, path,
                  ": not a foresight artifact (root attribute 'kind' is not '", kArtifactKind,
                  "')");
  const auto version = f.GetIntAttr("/", "format_version");
  FS_THROW_UNLESS(version == kArtifactFormatVersion, path, ": artifact format_version ", version,
                  " is not supported by this build (expected ", kArtifactFormatVersion, ")");
  a.model_type_ = f.GetStringAttr("/", "model_type");
  FS_THROW_UNLESS(expected_model_type.empty() || a.model_type_ == expected_model_type, path,
                  ": artifact holds a '", a.model_type_, "' model, expected '", expected_model_type,
                  "'");
  a.seed_ = f.GetIntAttr("/", "seed");
  a.config_yaml_ = f.ReadString("/config");
  return a;
}

int Artifact::IntAttr(const std::string& object, const std::string& name, int lo, int hi) const {
  const std::int64_t v = file_.GetIntAttr(object, name);
  FS_THROW_UNLESS(v >= lo && v <= hi, file_.path(), ": attribute ", object, "/", name, " is ", v,
                  "; expected ", lo, " to ", hi);
  return static_cast<int>(v);
}

double Artifact::DoubleAttr(const std::string& object, const std::string& name, double lo,
                            double hi) const {
  const double v = file_.GetDoubleAttr(object, name);
  FS_THROW_UNLESS(std::isfinite(v) && v >= lo && v <= hi, file_.path(), ": attribute ", object, "/",
                  name, " is ", v, "; expected a finite number from ", lo, " to ", hi);
  return v;
}

void Artifact::WriteHeader(h5::File* f, const std::string& model_type,
                           const std::string& config_yaml, std::int64_t seed) {
  f->SetAttr("/", "kind", std::string(kArtifactKind));
  f->SetAttr("/", "format_version", kArtifactFormatVersion);
  f->SetAttr("/", "model_type", model_type);
  f->SetAttr("/", "seed", seed);
  f->WriteString("/config", config_yaml);
}

}  // namespace foresight
