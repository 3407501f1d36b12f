// linespace-cpu: the command line of the CPU reference (docs/design.md §9; the subcommands and flags are
// cli_program.h's, shared with linespace-gpu).  Structures are built and traced on all CPU threads (or --threads),
// and bench runs Embree 3 beside them.
#include "cpu/app/cli_program.h"
#include "cpu/app/cpu_backend.h"
#include "cpu/trace/embree_tracer.h"

int main(int argc, char** argv) {
  ls::ProgramInfo info;
  info.name = "linespace-cpu";
  info.description = "linespace-cpu: exact and Line Space ray tracing, CPU reference";
  info.embree_isas = ls::embree_isa_names();
  info.make_backend = [](const std::string&) { return ls::make_cpu_backend(); };
  return ls::run_program(argc, argv, info);
}
