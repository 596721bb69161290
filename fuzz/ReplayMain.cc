// vxf_fuzz_replay TARGET PATH... — run a fuzz target (fuzz/Targets.h) over files and the files
// of folders, as libFuzzer would run them, without libFuzzer: for the test build, which replays
// each target's corpus and its findings (tests/regress/fuzz) so that they keep passing.
#include "Targets.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <vector>

int main(int argc, char** argv)
{
    namespace fs = std::filesystem;
    const auto& targets = vxf::fuzz::targets();
    const vxf::fuzz::NamedTarget* target = nullptr;
    for (const auto& t : targets) {
        if (argc > 1 && t.name == argv[1]) target = &t;
    }
    if (!target) {
        std::cerr << "usage: vxf_fuzz_replay TARGET PATH...; targets:";
        for (const auto& t : targets) std::cerr << " " << t.name;
        std::cerr << "\n";
        return 2;
    }
    std::vector<fs::path> files;
    for (int i = 2; i < argc; ++i) {
        if (fs::is_directory(argv[i])) {
            for (const auto& entry : fs::recursive_directory_iterator(argv[i])) {
                if (entry.is_regular_file()) files.push_back(entry.path());
            }
        } else if (fs::exists(argv[i])) {
            files.push_back(argv[i]);
        }
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
        std::ifstream in(file, std::ios::binary);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::cerr << file.string() << "\n"; // the input a crash below happened on
        target->run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    }
    std::cout << target->name << ": " << files.size() << " inputs replayed\n";
    return files.empty() ? 1 : 0; // a target without inputs tests nothing
}
