// lmd-eval: runs the evaluation protocol of DESIGN.md §4 on laser logs.
#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "-h" || command == "--help") {
    std::printf("usage: lmd-eval <command> [options]\n");
    return 0;
  }
  std::fprintf(stderr, "lmd-eval: no evaluation command is implemented yet\n");
  return 2;
}
