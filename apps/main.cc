// foresight: the command line. Thin: parse, dispatch; errors print one line and exit non-zero.

#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "training/kinds.h"

int main(int argc, char** argv) {
  CLI::App app{"foresight: learn, export and run robot perception and anticipation models"};
  app.require_subcommand(1);
  try {
    foresight::app::AddExperimentCommands(
        &app, std::make_shared<const foresight::ExperimentRegistry>(foresight::BuiltinKinds()));
    foresight::app::AddDataCommands(&app);
    foresight::app::AddMapCommands(&app);
    foresight::app::AddNavigateCommand(&app);
    foresight::app::AddPlanCommand(&app);
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "foresight: error: " << e.what() << " (see --help)\n";
    return 2;
  } catch (const foresight::Error& e) {
    std::cerr << "foresight: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    const std::string what = e.what();
    std::cerr << "foresight: error: " << what.substr(0, what.find('\n')) << "\n";
    return 1;
  }
  return 0;
}
