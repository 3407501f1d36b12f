// The progress line of the long commands (common/base/progress.h) end to end: on a terminal (a
// pseudo-terminal here) build, render and a validator study draw it on stderr, in linespace-gpu
// (lavapipe) too; with stderr a pipe they print nothing extra.
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>

#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <string>

using namespace test_support;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) { return temp_path("progress_cli", name); }

struct TerminalRun {
  int status = -1;
  std::string output;  // what the command wrote to the terminal
};

// Runs `command` with sh on a new pseudo-terminal (its stdin, stdout and stderr) and reads what it writes.
TerminalRun run_on_terminal(const std::string& command) {
  int master = -1;
  winsize size{};
  size.ws_row = 24;
  size.ws_col = 160;
  const pid_t pid = forkpty(&master, nullptr, nullptr, &size);
  REQUIRE(pid >= 0);
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  TerminalRun r;
  char buffer[4096];
  for (;;) {
    const ssize_t n = read(master, buffer, sizeof buffer);
    if (n > 0) r.output.append(buffer, size_t(n));
    else if (n < 0 && errno == EINTR) continue;
    else break;  // EIO: the terminal's other side is closed
  }
  int status = 0;
  waitpid(pid, &status, 0);
  close(master);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// stderr only (stdout to /dev/null): through a terminal, and through a pipe into a file.
struct BothWays {
  TerminalRun terminal;
  Run piped;
};
BothWays run_both_ways(const std::string& program, const std::string& args) {
  fs::create_directories(temp(""));
  BothWays b;
  b.terminal = run_on_terminal(program + " " + args + " >/dev/null");
  const std::string err = temp("piped_stderr").string();
  const int raw = std::system(("{ " + program + " " + args + " 2>&1 >/dev/null; } | cat >" + err).c_str());
  b.piped.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  b.piped.err = slurp(err);
  return b;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("render and build show a progress line on a terminal and print nothing extra into a pipe", "[progress_cli]") {
  const BothWays render = run_both_ways(LINESPACE_CPU, "render --scene builtin:cornell --size 16x16 --spp 3 --bounces 1 --out " +
                                                          temp("render").string());
  INFO("terminal: " << render.terminal.output << "\npiped: " << render.piped.err);
  REQUIRE(render.terminal.status == 0);
  REQUIRE(render.piped.status == 0);
  CHECK(contains(render.terminal.output, "\rrender ["));
  CHECK(contains(render.terminal.output, "] 3/3 samples"));
  CHECK(render.piped.err.empty());
  // --quiet: none on a terminal either.
  CHECK(!contains(run_on_terminal(std::string(LINESPACE_CPU) + " render --scene builtin:cornell --size 16x16 --spp 3 --bounces 1 "
                                  "--quiet --out " + temp("quiet").string() + " >/dev/null").output, "samples"));

  const BothWays build = run_both_ways(LINESPACE_CPU, "build --scene builtin:cornell --structure f-ls:4:4 --ls-min-triangles 0");
  INFO("terminal: " << build.terminal.output << "\npiped: " << build.piped.err);
  REQUIRE(build.terminal.status == 0);
  REQUIRE(build.piped.status == 0);
  CHECK(contains(build.terminal.output, "\rline space ["));
  CHECK(contains(build.terminal.output, "LS nodes"));
  CHECK(build.terminal.output.back() == '\n');  // the line is ended
  CHECK(build.piped.err.empty());
}

TEST_CASE("a validator study shows its renders' progress on a terminal, and only its log lines in a pipe", "[progress_cli]") {
  const std::string args = "rmse --scene builtin:cornell --structures f-ls:3:4 --size 16x16 --spp 2 --bounces 1 --out " +
                           temp("rmse").string();
  const BothWays study = run_both_ways(LINESPACE_VALIDATE, args);
  INFO("terminal: " << study.terminal.output << "\npiped: " << study.piped.err);
  REQUIRE(study.terminal.status == 0);
  REQUIRE(study.piped.status == 0);
  CHECK(contains(study.terminal.output, "\rrender ["));
  CHECK(contains(study.terminal.output, "samples"));
  CHECK(contains(study.terminal.output, "\r" + std::string(40, ' ')));  // a finished render's line is erased
  CHECK(!contains(study.piped.err, "\r"));
  CHECK(!contains(study.piped.err, "samples"));
  CHECK(contains(study.piped.err, "reference (bvh)"));  // the study's own log is still there
}

TEST_CASE("linespace-gpu's Line Space search and render show the progress line on a terminal, not in a pipe", "[progress_cli]") {
  const BothWays build = run_both_ways(LINESPACE_GPU, "build --scene builtin:cornell --structure f-ls:5:4 --ls-min-triangles 0");
  INFO("terminal: " << build.terminal.output << "\npiped: " << build.piped.err);
  REQUIRE(build.terminal.status == 0);
  REQUIRE(build.piped.status == 0);
  CHECK(contains(build.terminal.output, "\rline space ["));
  CHECK(build.piped.err.empty());
  const BothWays render = run_both_ways(LINESPACE_GPU, "render --scene builtin:cornell --size 16x16 --spp 2 --bounces 1 --out " +
                                                          temp("gpu_render").string());
  INFO("terminal: " << render.terminal.output << "\npiped: " << render.piped.err);
  REQUIRE(render.terminal.status == 0);
  REQUIRE(render.piped.status == 0);
  CHECK(contains(render.terminal.output, "] 2/2 samples"));
  CHECK(render.piped.err.empty());
}
