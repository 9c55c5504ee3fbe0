// lmd-bench: index scale and server load benchmarks.
#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "-h" || command == "--help") {
    std::printf("usage: lmd-bench <command> [options]\n");
    return 0;
  }
  std::fprintf(stderr, "lmd-bench: no benchmark command is implemented yet\n");
  return 2;
}
