#pragma once
// The trainee model hattr ships (data/sim/trainee_model.json), read once per test program.

#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/trainee_model.hpp"

namespace hattr::test {

inline const sim::TraineeModel& shippedModel() {
  static const sim::TraineeModel model = sim::loadTraineeModel(sim::defaultDataDir() / "sim" / "trainee_model.json");
  return model;
}

}  // namespace hattr::test
