#pragma once
// What the commands that run an engine (relax, pour, settle) share: the libraries' exceptions turned into the
// exit codes, with one line "btr COMMAND: ..." on stderr.
#include <iostream>
#include <stdexcept>

#include "btr/scene/scene_toml.h"
#include "commands.h"
#include "coupling/dem/process.h"
#include "coupling/dem/relax.h"
#include "coupling/dem/relax_plan.h"

namespace btr_app {

// Runs `body` (which returns an exit code): a stop signal becomes 128 + N, an engine failure kEngineFailed, a bad
// scene or a refused setting kBadInput, anything else `other_code`.
template <class Body>
int run_engine_command(const char* command, int other_code, Body&& body) {
  auto fail = [&](const std::exception& e, int code) {
    std::cerr << "btr " << command << ": " << e.what() << "\n";
    return code;
  };
  try {
    return body();
  } catch (const btr::Interrupted& e) {
    return fail(e, interrupted_exit_code(e.signal()));
  } catch (const btr::EngineFailure& e) {
    return fail(e, kEngineFailed);
  } catch (const btr::SceneError& e) {
    return fail(e, kBadInput);
  } catch (const btr::RelaxRefused& e) {
    return fail(e, kBadInput);
  } catch (const std::exception& e) {
    return fail(e, other_code);
  }
}

}  // namespace btr_app
