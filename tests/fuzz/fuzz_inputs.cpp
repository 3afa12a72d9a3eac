// libFuzzer target for every reader of user files: the first byte picks the reader (scene, Gmsh,
// TetGen, OBJ), the rest is the file. A reader may accept the input or throw InputError; the
// message must be one line naming the file. Anything else (another exception, a crash, a
// sanitizer report) is a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "apps/scene.hpp"
#include "core/error.hpp"
#include "core/gmsh_reader.hpp"
#include "core/obj_reader.hpp"
#include "core/tetgen_reader.hpp"

namespace {

std::filesystem::path work_folder() {
  return std::filesystem::temp_directory_path() /
         ("depthfem_fuzz_inputs_" + std::to_string(getpid()));
}

void write(const std::string& path, std::string_view text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Aborts (a finding) unless `message` is one line that starts with `file`.
void check_located(const std::string& message, const std::string& file) {
  if (message.rfind(file, 0) != 0 || message.find('\n') != std::string::npos) {
    std::fprintf(stderr, "unlocated or multi-line message: %s\n", message.c_str());
    std::abort();
  }
}

}  // namespace

// The inputs are written into a fresh folder, removed at exit.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::filesystem::create_directories(work_folder());
  std::atexit([] { std::filesystem::remove_all(work_folder()); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::string base = (work_folder() / "input").string();
  std::string file;
  try {
    switch (data[0] % 4) {
      case 0:
        file = base + ".json";
        write(file, text);
        depthfem::load_scene(file);
        break;
      case 1:
        file = base + ".msh";
        write(file, text);
        depthfem::read_gmsh(file);
        break;
      case 2: {  // .node, then .ele after the first form feed
        const size_t split = text.find('\f');
        file = base;
        write(base + ".node", text.substr(0, split));
        write(base + ".ele", split == std::string_view::npos ? "" : text.substr(split + 1));
        depthfem::read_tetgen(base + ".node");
        break;
      }
      case 3:
        file = base + ".obj";
        write(file, text);
        depthfem::read_obj(file);
        break;
    }
  } catch (const depthfem::InputError& e) {
    check_located(e.what(), file);
  }
  return 0;
}
