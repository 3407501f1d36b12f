// Runs one of our programs as a user would, capturing its exit status, stdout and stderr.  Each test
// process works in its own folder: ctest runs test cases in parallel.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace test_support {

struct Run {
  int status = -1;
  std::string out, err;
};

inline std::filesystem::path temp_path(const std::string& tag, const std::string& name) {
  return std::filesystem::temp_directory_path() / ("linespace_" + tag + "_" + std::to_string(getpid())) / name;
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

inline Run run_program(const std::string& program, const std::string& args, const std::string& tag) {
  std::filesystem::create_directories(temp_path(tag, ""));
  const std::string out = temp_path(tag, "stdout").string(), err = temp_path(tag, "stderr").string();
  const int raw = std::system((program + " " + args + " >" + out + " 2>" + err).c_str());
  Run r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace test_support
