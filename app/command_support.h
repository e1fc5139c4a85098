#pragma once
// What the scene-driven subcommands (deposit, shake, drum) share: turning the libraries' exceptions
// into the exit codes, checking the output name, and reporting the self-check the same way.
#include <iostream>
#include <new>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "btr/placement/deposition.h"
#include "btr/scene/scene_toml.h"
#include "btr/verify/check.h"
#include "commands.h"

namespace btr_app {

// Runs `body` (which returns an exit code); a SceneError or a full container (more grains than it holds)
// becomes kBadInput, a PlacementError or any other exception kInternalFailure, each with one line
// "btr COMMAND: ..." on stderr.
template <class Body>
int run_reporting_errors(const char* command, Body&& body) {
  try {
    return body();
  } catch (const btr::SceneError& e) {
    std::cerr << "btr " << command << ": " << e.what() << "\n";
    return kBadInput;
  } catch (const btr::ContainerFull& e) {
    std::cerr << "btr " << command << ": grains.count: expected at most " << e.grain_id() - 1
              << " grains, the number the drum held when it was full (" << e.what() << ")\n";
    return kBadInput;
  } catch (const btr::PlacementError& e) {
    std::cerr << "btr " << command << ": placement failed: " << e.what() << "\n";
    return kInternalFailure;
  } catch (const std::bad_alloc&) {
    // The size checks (btr/scene/size_budget.h) refuse what cannot fit before anything is allocated; this is a
    // run that fit the estimate but not the memory free now (other jobs share the machine).
    std::cerr << "btr " << command << ": out of memory: the run needed more than this machine had free; "
              << "run it with fewer grains or when other jobs have ended\n";
    return kInternalFailure;
  } catch (const std::exception& e) {
    std::cerr << "btr " << command << ": " << e.what() << "\n";
    return kInternalFailure;
  }
}

// The base name of the output files: `--name`, else the scene's. Throws a SceneError naming --name when it
// is empty or holds a '/'.
std::string output_name(const std::string& option, const btr::Scene& scene);

// The self-check as stored in the packing JSON (key "check").
nlohmann::json check_to_json(const btr::CheckReport& c);

// One line for the console: counts, the largest overlap and a few offending grains.
std::string check_message(const btr::CheckReport& c);

}  // namespace btr_app
