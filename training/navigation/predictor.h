#pragma once
/// Trains the SPAN predictor a navigation config asks for when its artifact does not exist yet:
/// tracks (the scenario's simulated crowd without the robot, or a recorded replay file) are written
/// to a track store beside the artifact, then the SPAN pipeline (train -> export -> eval) runs on
/// them with the config's `predictor.train_config`. Needs LibTorch.

#include <string>

#include "training/navigation/config.h"

namespace foresight::nav {

/// Ensures config.predictor.artifact exists (trains it in its directory, which must be the run
/// directory of a SPAN run: the artifact is named model.h5). A killed training resumes from its
/// last checkpoint. @return the artifact path.
/// @param embedded_default SPAN config text used when predictor.train_config is "default".
std::string EnsurePredictor(const ExperimentConfig& config, const std::string& embedded_default);

}  // namespace foresight::nav
