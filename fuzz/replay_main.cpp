// The replay driver of the fuzz harnesses: runs LLVMFuzzerTestOneInput once on
// every file named on the command line (directories: every file in them, in
// name order). Built with each harness as a plain executable, so that the seed
// corpus and every kept crashing input (fuzz/regressions/HARNESS/) run as a
// ctest regression test. The afl++ build links libAFLDriver instead (scripts/fuzz).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

int replay_file(const std::filesystem::path& path)
{
    std::ifstream file(path, std::ios::binary);
    if (!file) {
        std::fprintf(stderr, "cannot read %s\n", path.c_str());
        return 1;
    }
    std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "replaying %s (%zu bytes)\n", path.c_str(), bytes.size());
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    int failures = 0, replayed = 0;
    for (int i = 1; i < argc; ++i) {
        std::filesystem::path argument(argv[i]);
        std::vector<std::filesystem::path> files;
        if (std::filesystem::is_directory(argument)) {
            for (const auto& entry : std::filesystem::directory_iterator(argument))
                if (entry.is_regular_file() && entry.path().filename().string()[0] != '.')
                    files.push_back(entry.path());
            std::sort(files.begin(), files.end());
        } else {
            files.push_back(argument);
        }
        for (const auto& file : files) {
            failures += replay_file(file);
            ++replayed;
        }
    }
    std::fprintf(stderr, "replayed %d inputs without a crash\n", replayed);
    return failures == 0 ? 0 : 1;
}
