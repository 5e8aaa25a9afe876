// Hash probe: runs a fixed set of scenes for a fixed number of steps and prints the state
// hash of each as CSV (case,steps,hash). A change that should not move any number (a
// restructure, a speed-up) must leave every line the same; tests/core/hash_probe_test.cpp
// keeps the expected lines. Extra `--set key=value` arguments apply to every case.
//
//   build/bench/hash_probe [--set key=value ...]
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "hash_probe.h"

int main(int argc, char** argv) {
  std::vector<std::string> extra;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--set") == 0 && i + 1 < argc) {
      extra.push_back(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: hash_probe [--set key=value ...]\n");
      return 2;
    }
  }
  std::printf("case,steps,hash\n");
  for (const auto& c : ravel::probe_cases()) {
    const auto r = ravel::run_probe(c, extra);
    std::printf("%s,%ld,%016llx\n", c.name.c_str(), r.steps, static_cast<unsigned long long>(r.hash));
  }
  return 0;
}
