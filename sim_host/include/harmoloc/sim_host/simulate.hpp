#pragma once
/// @file Writes a complete dataset folder for a scenario run: frames, frame index, encoder log,
/// ground truth, labels, kidnaps and metadata.

#include <cstdint>
#include <functional>
#include <string>

#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host {

struct SimulationSummary {
  std::size_t frames = 0;
  std::size_t encoder_frames = 0;
  std::size_t labels = 0;
  std::size_t kidnaps = 0;
  RouteStats route;
};

/// Renders a ScenarioRun of @p scenario with @p seed into @p out_dir (created; existing files are
/// overwritten). kidnaps.csv is written when the run has kidnaps. @p progress is called with
/// (frames done, frames total) now and then.
SimulationSummary simulate_dataset(const Scenario& scenario, std::uint64_t seed,
                                   const std::string& out_dir,
                                   const std::function<void(std::size_t, std::size_t)>& progress);

}  // namespace harmoloc::sim_host
