// Replays fuzz inputs through LLVMFuzzerTestOneInput without libFuzzer (any compiler): every file
// given, or every file in every folder given. Used by ctest to keep the corpus and every input that
// once crashed or hung a reader as regression tests. Exit status 0 when all ran, each within the
// 10 s that the fuzz runs allow one input (scripts/fuzz: -timeout=10); a finding aborts.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    for (int i = 1; i < argc; ++i) {
        const fs::path p(argv[i]);
        if (fs::is_directory(p)) {
            for (const auto& e : fs::recursive_directory_iterator(p))
                if (e.is_regular_file()) files.push_back(e.path());
        } else if (fs::is_regular_file(p)) {
            files.push_back(p);
        }
    }
    std::sort(files.begin(), files.end());
    int slow = 0;
    for (const fs::path& f : files) {
        std::ifstream in(f, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const auto t0 = std::chrono::steady_clock::now();
        LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (s > 10.0) {
            std::printf("%s: took %.1f s, more than the 10 s a fuzz run allows one input (a hang)\n",
                        f.string().c_str(), s);
            ++slow;
        }
    }
    std::printf("replayed %zu inputs\n", files.size());
    return files.empty() || slow ? 1 : 0;
}
