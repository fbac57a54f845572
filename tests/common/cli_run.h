// Running the built `shimmer` binary from a test: its exit code and what it
// printed (stdout and stderr together), for the CLI tests of every library.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace shimmer::testing {

struct CliRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// `shimmer ARGS` through the shell, with `env` set (XDG_RUNTIME_DIR for lavapipe).
inline CliRun RunShimmer(const std::string& shimmer, const std::string& args,
                         const std::string& env = "XDG_RUNTIME_DIR=/tmp") {
  const std::string cmd = "env " + env + " " + shimmer + " " + args + " 2>&1";
  CliRun r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace shimmer::testing
