// Clean interruption (Ctrl-C, SIGTERM).  The programs install the handlers; long loops (BVH and Line
// Space builders, the path tracer's passes and bounces, output writing) poll interrupt_requested()
// at points where stopping loses nothing but the work in progress, and throw Interrupted.  The
// program then exits 130 with one line, having written no output file (outputs are written to a
// temporary name and renamed, and none is started once an interrupt is pending).  A second signal
// ends the process at once (after removing the temporary file being written, if any).
#pragma once

#include <stdexcept>
#include <string>

namespace ls {

struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void install_interrupt_handlers();   // SIGINT and SIGTERM
bool interrupt_requested();
int interrupt_signal();              // the signal received, 0 if none
void request_interrupt(int signal);  // as if `signal` had arrived (tests)
void clear_interrupt();              // tests
void throw_if_interrupted();         // throws Interrupted when one is pending

// The file being written right now, removed if a second signal ends the process (nullptr: none).
// The path is copied into a fixed buffer, so the signal handler needs no allocation.
void set_partial_file(const std::string* path);

}  // namespace ls
