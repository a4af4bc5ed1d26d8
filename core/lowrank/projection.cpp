#include "core/lowrank/projection.h"

#include "core/common/avx2_clones.h"
#include "core/common/error.h"
#include "core/lowrank/tiles.h"

#include <algorithm>
#include <string>
#include <vector>

namespace modestack::lowrank {
namespace {

void check_shapes(std::int64_t rows_in, int frames_in, std::int64_t rows_out, int frames_out,
                  const char* what)
{
    if (rows_in != rows_out || frames_in != frames_out)
        throw internal_error(std::string(what) + ": band shapes do not match the basis");
}

void write_tile(const Eigen::MatrixXd& values, std::int64_t row0, MutableBandView out)
{
    for (Eigen::Index f = 0; f < values.cols(); ++f) {
        float* target = out.data + f * out.frame_stride + row0;
        const double* source = values.col(f).data();
        for (Eigen::Index i = 0; i < values.rows(); ++i)
            target[i] = static_cast<float>(source[i]);
    }
}

} // namespace

void project_band(const BandView& in, const Eigen::MatrixXd& temporal_n, MutableBandView out)
{
    check_shapes(in.rows, in.frames, out.rows, out.frames, "project_band");
    if (temporal_n.rows() != in.frames)
        throw internal_error("project_band: basis has the wrong number of frames");
    for_each_tile(in.rows, [&](std::int64_t row0, std::int64_t count) {
        Eigen::MatrixXd tile;
        copy_tile(in, row0, count, tile);
        const Eigen::MatrixXd coefficients = tile * temporal_n;
        const Eigen::MatrixXd rebuilt = coefficients * temporal_n.transpose();
        write_tile(rebuilt, row0, out);
    });
}

void project_coefficients(const BandView& in, const Eigen::MatrixXd& temporal_n, MutableBandView coefficients)
{
    check_shapes(in.rows, static_cast<int>(temporal_n.cols()), coefficients.rows, coefficients.frames,
                 "project_coefficients");
    if (temporal_n.rows() != in.frames)
        throw internal_error("project_coefficients: basis has the wrong number of frames");
    for_each_tile(in.rows, [&](std::int64_t row0, std::int64_t count) {
        Eigen::MatrixXd tile;
        copy_tile(in, row0, count, tile);
        write_tile(tile * temporal_n, row0, coefficients);
    });
}

namespace {

// Rows [row0, row0 + count) of every frame of `out`, `sum` their scratch.
MODESTACK_AVX2_CLONES void rebuild_tile(const BandView& coefficients, const Eigen::MatrixXd& temporal_n,
                                        const MutableBandView& out, std::int64_t row0, std::int64_t count,
                                        double* sum)
{
    for (int t = 0; t < out.frames; ++t) {
        std::fill(sum, sum + count, 0.0);
        for (int j = 0; j < coefficients.frames; ++j) {
            const double weight = temporal_n(t, j);
            const float* c = coefficients.data + j * coefficients.frame_stride + row0;
            for (std::int64_t i = 0; i < count; ++i)
                sum[i] += static_cast<double>(c[i]) * weight;
        }
        float* target = out.data + t * out.frame_stride + row0;
        for (std::int64_t i = 0; i < count; ++i)
            target[i] = static_cast<float>(sum[i]);
    }
}

}  // namespace

void rebuild_from_coefficients(const BandView& coefficients, const Eigen::MatrixXd& temporal_n,
                               MutableBandView out)
{
    check_shapes(coefficients.rows, static_cast<int>(temporal_n.rows()), out.rows, out.frames,
                 "rebuild_from_coefficients");
    if (temporal_n.cols() != coefficients.frames)
        throw internal_error("rebuild_from_coefficients: basis has the wrong number of modes");
    // Each value is Σ_j c_j V_tj summed in mode order in double, whatever the tile
    // and the frames asked for (no GEMM kernel whose order depends on the sizes):
    // a farm write task rebuilding one frame gets the bits of a whole run.
    for_each_tile(coefficients.rows, [&](std::int64_t row0, std::int64_t count) {
        std::vector<double> sum(static_cast<std::size_t>(count));
        rebuild_tile(coefficients, temporal_n, out, row0, count, sum.data());
    });
}

} // namespace modestack::lowrank
