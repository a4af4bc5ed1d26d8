#include "io/text_output.h"

#include "core/common/error.h"
#include "io/temporary_file.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <system_error>

namespace modestack::io {

void write_text_file(const std::string& path, const std::string& text)
{
    namespace stdfs = std::filesystem;
    stdfs::path target(path);
    std::error_code error;
    if (target.has_parent_path())
        stdfs::create_directories(target.parent_path(), error);
    remove_stale_temporaries(path);
    std::string temporary = temporary_path_for(path);
    std::FILE* file = std::fopen(temporary.c_str(), "wb");
    if (!file)
        throw bad_input(path, "cannot create file");
    bool ok = std::fwrite(text.data(), 1, text.size(), file) == text.size();
    ok = std::fclose(file) == 0 && ok;
    if (ok)
        stdfs::rename(temporary, target, error);
    if (!ok || error) {
        stdfs::remove(temporary, error);
        throw bad_input(path, "cannot write file");
    }
}

void set_io_threads(int threads)
{
    OIIO::attribute("threads", threads);
    OIIO::attribute("exr_threads", threads);
}

void use_single_threaded_exr_files()
{
    OIIO::attribute("exr_threads", -1);  // OIIO: -1 = no OpenEXR worker threads
}

}  // namespace modestack::io
