#include "io/stage_files.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>

namespace modestack::io {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "stage files hold little-endian doubles");

// The first line of every stage file. Its number changes with the layout: 2 added
// the input's roughness (statistics) and each frame's noise factor (solve).
// 3: survey rows count each mode's high-pass ratios; 4: modes files hold each row's bias posterior;
// 5: the survey and modes are of the modes fitted to each frame's measured noise (frame_weighting.h),
// statistics files hold the cleaned input's roughness and solve files the frame scales' factors.
constexpr const char* kMagic = "modestack stage file 5";
constexpr const char* kMagicPrefix = "modestack stage file ";

// Throws a one-line error unless `line` is this version's first line.
void check_magic(const std::string& path, const std::string& line)
{
    if (line == kMagic)
        return;
    if (line.rfind(kMagicPrefix, 0) == 0)
        throw bad_input(path,
                        fmt::format("was written by another modestack (stage file {}, this one reads {}): "
                                    "run every task of a job with the same modestack",
                                    line.substr(std::string(kMagicPrefix).size()),
                                    std::string(kMagic).substr(std::string(kMagicPrefix).size())));
    throw bad_input(path, "not a modestack stage file");
}

// The numbers of a file, appended in order.
class Payload {
public:
    void add(double value) { m_bytes.append(reinterpret_cast<const char*>(&value), sizeof value); }
    void add_lower(const Eigen::MatrixXd& matrix)
    {
        for (Eigen::Index j = 0; j < matrix.cols(); ++j)
            for (Eigen::Index i = j; i < matrix.rows(); ++i)
                add(matrix(i, j));
    }
    void add_gram(const lowrank::GramAccumulator& gram)
    {
        const lowrank::GramAccumulator::State state = gram.state();
        add_lower(state.gram);
        add_lower(state.half_gram[0]);
        add_lower(state.half_gram[1]);
        for (Eigen::Index i = 0; i < state.frame_sum.size(); ++i)
            add(state.frame_sum[i]);
    }
    /// Floats follow every double in the file.
    void add_floats(const std::vector<float>& values)
    {
        if (!values.empty())  // an empty vector's data() may be null
            m_floats.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
    }
    std::size_t doubles() const { return m_bytes.size() / sizeof(double); }
    std::size_t floats() const { return m_floats.size() / sizeof(float); }
    std::string bytes() const { return m_bytes + m_floats; }

private:
    std::string m_bytes;
    std::string m_floats;
};

// Doubles per Gram accumulator of `frames` frames (see Payload::add_gram).
std::size_t gram_doubles(int frames) { return 3 * static_cast<std::size_t>(frames) * (frames + 1) / 2 + frames; }

// Reads the numbers of a file back, in the order they were added.
class PayloadReader {
public:
    PayloadReader(const char* data, std::size_t doubles) : m_data(data), m_left(doubles), m_floats(data + doubles * sizeof(double)) {}
    double next()
    {
        if (m_left == 0)
            throw internal_error("stage file payload read past its end");
        double value;
        std::memcpy(&value, m_data, sizeof value);
        m_data += sizeof value;
        --m_left;
        return value;
    }
    Eigen::MatrixXd lower(int size)
    {
        Eigen::MatrixXd matrix(size, size);
        for (int j = 0; j < size; ++j)
            for (int i = j; i < size; ++i)
                matrix(i, j) = matrix(j, i) = next();
        return matrix;
    }
    /// The next `count` floats of the float part.
    std::vector<float> floats(std::size_t count)
    {
        std::vector<float> values(count);
        if (count > 0)  // memcpy from or to null is undefined even for 0 bytes
            std::memcpy(values.data(), m_floats, count * sizeof(float));
        m_floats += count * sizeof(float);
        return values;
    }
    lowrank::GramAccumulator gram(int frames, std::int64_t rows, std::int64_t tiles)
    {
        lowrank::GramAccumulator::State state;
        state.gram = lower(frames);
        state.half_gram[0] = lower(frames);
        state.half_gram[1] = lower(frames);
        state.frame_sum.resize(frames);
        for (int i = 0; i < frames; ++i)
            state.frame_sum[i] = next();
        state.rows = rows;
        state.tiles = tiles;
        return lowrank::GramAccumulator::from_state(state);
    }

private:
    const char* m_data;
    std::size_t m_left;
    const char* m_floats;
};

std::string stage_bytes(nlohmann::ordered_json header, const Payload& payload)
{
    header["doubles"] = payload.doubles();
    if (payload.floats() > 0)
        header["floats"] = payload.floats();
    return std::string(kMagic) + "\n" + header.dump() + "\n" + payload.bytes();
}

nlohmann::ordered_json header_for(denoise::Stage stage, const ShotFingerprint& fingerprint, int frames)
{
    nlohmann::ordered_json header;
    header["stage"] = denoise::stage_name(stage);
    header["shot"] = fingerprint.shot;
    header["options"] = fingerprint.options;
    header["frames"] = frames;
    return header;
}

nlohmann::ordered_json outliers_json(const lowrank::OutlierCounts& counts)
{
    return {{"non_finite", counts.non_finite}, {"fireflies", counts.fireflies}};
}

// A stage file read whole: its header and where its numbers start.
struct StageFile {
    std::string path;
    std::string bytes;
    nlohmann::json header;
    std::size_t payload_offset = 0;

    PayloadReader payload() const
    {
        return {bytes.data() + payload_offset, header.at("doubles").get<std::size_t>()};
    }
};

// The first key of `expected` whose value differs in `found` (or is missing).
std::string first_difference(const nlohmann::json& expected, const nlohmann::json& found)
{
    for (auto it = expected.begin(); it != expected.end(); ++it)
        if (!found.contains(it.key()) || found.at(it.key()) != it.value())
            return it.key();
    for (auto it = found.begin(); it != found.end(); ++it)
        if (!expected.contains(it.key()))
            return it.key();
    return {};
}

std::string read_whole_file(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw bad_input(path, "cannot open the stage file");
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// Checks that `bytes` (named `path` in errors) are a `stage` file of this shot and options.
StageFile parse_stage_file(const std::string& path, std::string bytes, denoise::Stage stage,
                           const ShotFingerprint& fingerprint)
{
    StageFile file{path, std::move(bytes), {}, 0};
    const std::size_t magic_end = file.bytes.find('\n');
    if (magic_end == std::string::npos)
        throw bad_input(path, "not a modestack stage file");
    check_magic(path, file.bytes.substr(0, magic_end));
    const std::size_t header_end = file.bytes.find('\n', magic_end + 1);
    if (header_end == std::string::npos)
        throw bad_input(path, "damaged stage file: its header is cut off");
    try {
        file.header = nlohmann::json::parse(file.bytes.substr(magic_end + 1, header_end - magic_end - 1));
        file.payload_offset = header_end + 1;
        const std::string found = file.header.at("stage").get<std::string>();
        if (found != denoise::stage_name(stage))
            throw bad_input(path, fmt::format("is the output of --stage {}, not of --stage {}", found,
                                              denoise::stage_name(stage)));
        if (file.bytes.size() - file.payload_offset != file.header.at("doubles").get<std::size_t>() * sizeof(double) +
                                                           file.header.value("floats", std::size_t(0)) * sizeof(float))
            throw bad_input(path, "damaged stage file: its size does not match its header (cut off?)");
        const nlohmann::json shot = fingerprint.shot, options = fingerprint.options;
        if (file.header.at("shot") != shot)
            throw bad_input(path, fmt::format("belongs to another shot: its {} differ from this command's input",
                                              first_difference(shot, file.header.at("shot"))));
        if (file.header.at("options") != options)
            throw bad_input(path, fmt::format("was made with other options: {} differs from this command's "
                                              "(give every task of a job the same options)",
                                              first_difference(options, file.header.at("options"))));
    } catch (const nlohmann::json::exception& error) {
        throw bad_input(path, fmt::format("damaged stage file header: {}", error.what()));
    }
    return file;
}

// The rows [begin, end) a file of a job holds.
struct RowBand {
    int begin, end;
    std::size_t file;
};

// Sorts `bands` by row and checks that they hold every row of a shot of
// `height` rows exactly once; errors name the file (`kind`: "statistics", "modes").
void check_row_coverage(std::vector<RowBand>& bands, const std::vector<StageFile>& files, int height,
                        const std::string& kind)
{
    std::sort(bands.begin(), bands.end(), [](const RowBand& a, const RowBand& b) { return a.begin < b.begin; });
    int covered = 0;
    for (const RowBand& band : bands) {
        const std::string& path = files[band.file].path;
        if (band.begin < covered) {
            auto other = std::find_if(bands.begin(), bands.end(), [&](const RowBand& b) {
                return &b != &band && b.begin < band.end && band.begin < b.end;
            });
            throw bad_input(path, fmt::format("rows {}-{} are also in {}: each band of rows must be given once",
                                              band.begin, band.end - 1, files[other->file].path));
        }
        if (band.begin > covered)
            throw bad_input(path, fmt::format("rows {}-{} are in no {} file given", covered, band.begin - 1, kind));
        covered = band.end;
    }
    if (covered < height)
        throw bad_input(files[bands.back().file].path,
                        fmt::format("rows {}-{} are in no {} file given", covered, height - 1, kind));
}

// FNV-1a of `bytes`, in hex: how survey and modes files name the solve file
// and the survey sums they were made from.
std::string digest_of(const std::string& bytes)
{
    std::uint64_t hash = 1469598103934665603ull;
    for (unsigned char c : bytes)
        hash = (hash ^ c) * 1099511628211ull;
    return fmt::format("{:016x}", hash);
}

// The files of one row-split stage of a job, checked: each a `stage` file of
// this shot and options holding rows [begin, end) of a shot of `height` rows,
// made from `solve` when given (its "solve" digest), and `fits` its header
// (fits(path, header, begin, end) false: "damaged <kind> file"; it may throw
// its own error); together they hold every row exactly once.
// `bands` come sorted by row.
struct RowFiles {
    std::vector<StageFile> files;
    std::vector<RowBand> bands;
};

template <typename Fits>
RowFiles read_row_files(const std::vector<StageBytes>& inputs, denoise::Stage stage, const ShotFingerprint& fingerprint,
                        int height, const std::string& kind, const StageBytes* solve, Fits&& fits)
{
    RowFiles result;
    const std::string solve_digest = solve ? digest_of(solve->bytes) : std::string();
    for (const StageBytes& input : inputs) {
        const std::string& path = input.name;
        result.files.push_back(parse_stage_file(path, input.bytes, stage, fingerprint));
        const nlohmann::json& header = result.files.back().header;
        try {
            if (solve && header.at("solve").get<std::string>() != solve_digest)
                throw bad_input(path, fmt::format("was made from another solve file than {}", solve->name));
            const int begin = header.at("rows").at(0).get<int>(), end = header.at("rows").at(1).get<int>();
            if (begin < 0 || end > height || begin >= end || !fits(path, header, begin, end))
                throw bad_input(path, fmt::format("damaged {} file: its sizes do not fit the shot", kind));
            result.bands.push_back({begin, end, result.files.size() - 1});
        } catch (const nlohmann::json::exception& error) {
            throw bad_input(path, fmt::format("damaged stage file header: {}", error.what()));
        }
    }
    check_row_coverage(result.bands, result.files, height, kind);
    return result;
}

}  // namespace

std::string shot_frames_of_solve_file(const StageBytes& solve)
{
    const std::string& path = solve.name;
    std::istringstream in(solve.bytes);
    std::string magic, header;
    if (!std::getline(in, magic))
        throw bad_input(path, "not a modestack stage file");
    check_magic(path, magic);
    if (!std::getline(in, header))
        throw bad_input(path, "not a modestack stage file");
    try {
        const nlohmann::json json = nlohmann::json::parse(header);
        if (json.at("stage").get<std::string>() != denoise::stage_name(denoise::Stage::Solve))
            throw bad_input(path, fmt::format("is the output of --stage {}, not of --stage solve",
                                              json.at("stage").get<std::string>()));
        return json.at("shot").at("frames").get<std::string>();
    } catch (const nlohmann::json::exception& error) {
        throw bad_input(path, fmt::format("damaged stage file header: {}", error.what()));
    }
}

StageBytes read_stage_bytes(const std::string& path) { return {path, read_whole_file(path)}; }

std::string statistics_bytes(const ShotFingerprint& fingerprint, const denoise::Statistics& statistics)
{
    const int frames = statistics.blocks.empty() ? 0 : statistics.blocks.front().frames();
    nlohmann::ordered_json header = header_for(denoise::Stage::Statistics, fingerprint, frames);
    header["rows"] = {statistics.row_begin, statistics.row_end};
    header["block_rows"] = denoise::kStageBlockRows;
    header["outliers"] = outliers_json(statistics.outliers);
    header["roughness"] = statistics.roughness; // [block][frame]; JSON doubles round-trip exactly
    header["cleaned_roughness"] = statistics.cleaned_roughness;
    nlohmann::ordered_json blocks = nlohmann::ordered_json::array();
    Payload payload;
    for (const lowrank::GramAccumulator& block : statistics.blocks) {
        const lowrank::GramAccumulator::State state = block.state();
        blocks.push_back({{"rows", state.rows}, {"tiles", state.tiles}});
        payload.add_gram(block);
    }
    header["blocks"] = blocks;
    return stage_bytes(header, payload);
}

denoise::Statistics read_statistics(const std::vector<StageBytes>& inputs, const ShotFingerprint& fingerprint,
                                    int height, int frames)
{
    if (inputs.empty())
        throw usage_error("--stage solve needs the statistics files of the job: --stats FILE...");
    const auto [files, bands] = read_row_files(
        inputs, denoise::Stage::Statistics, fingerprint, height, "statistics", nullptr,
        [&](const std::string&, const nlohmann::json& header, int begin, int end) {
            const int blocks = denoise::stage_blocks(end - begin);
            return header.at("frames").get<int>() == frames &&
                   header.at("block_rows").get<int>() == denoise::kStageBlockRows &&
                   static_cast<int>(header.at("blocks").size()) == blocks &&
                   header.at("roughness").size() == static_cast<size_t>(blocks) * frames &&
                   header.at("cleaned_roughness").size() == static_cast<size_t>(blocks) * frames &&
                   header.at("doubles").get<std::size_t>() == blocks * gram_doubles(frames);
        });
    denoise::Statistics shot;
    shot.row_begin = 0;
    shot.row_end = height;
    for (const RowBand& band : bands) {
        const StageFile& file = files[band.file];
        PayloadReader payload = file.payload();
        for (const nlohmann::json& block : file.header.at("blocks"))
            shot.blocks.push_back(
                payload.gram(frames, block.at("rows").get<std::int64_t>(), block.at("tiles").get<std::int64_t>()));
        shot.outliers.non_finite += file.header.at("outliers").at("non_finite").get<std::int64_t>();
        shot.outliers.fireflies += file.header.at("outliers").at("fireflies").get<std::int64_t>();
        for (const nlohmann::json& value : file.header.at("roughness"))
            shot.roughness.push_back(value.get<double>());
        for (const nlohmann::json& value : file.header.at("cleaned_roughness"))
            shot.cleaned_roughness.push_back(value.get<double>());
    }
    return shot;
}

std::string solve_bytes(const ShotFingerprint& fingerprint, const denoise::SolvedSums& solved)
{
    const lowrank::GramAccumulator::State state = solved.gram.state();
    nlohmann::ordered_json header = header_for(denoise::Stage::Solve, fingerprint, solved.gram.frames());
    header["gram"] = {{"rows", state.rows}, {"tiles", state.tiles}};
    header["outliers"] = outliers_json(solved.outliers);
    header["frame_noise_factors"] = solved.frame_noise_factors;
    header["frame_scale_factors"] = solved.frame_scale_factors;
    const denoise::RepeatingNoise& repeating = solved.repeating;
    header["repeating_noise"] = {{"measured", repeating.measured}, {"temporal", repeating.temporal},
                                 {"spatial", repeating.spatial},   {"coarse", repeating.coarse},
                                 {"share", repeating.share},       {"whiteness", repeating.whiteness},
                                 {"level", repeating.level},       {"repeats", repeating.repeats},
                                 {"frames", repeating.frames}};
    Payload payload;
    payload.add_gram(solved.gram);
    return stage_bytes(header, payload);
}

denoise::SolvedSums read_solve(const StageBytes& solve, const ShotFingerprint& fingerprint)
{
    const std::string& path = solve.name;
    StageFile file = parse_stage_file(path, solve.bytes, denoise::Stage::Solve, fingerprint);
    try {
        const int frames = file.header.at("frames").get<int>();
        if (frames < 1 || file.header.at("doubles").get<std::size_t>() != gram_doubles(frames))
            throw bad_input(path, "damaged solve file: its sizes do not agree");
        PayloadReader payload = file.payload();
        denoise::SolvedSums solved;
        solved.gram = payload.gram(frames, file.header.at("gram").at("rows").get<std::int64_t>(),
                                   file.header.at("gram").at("tiles").get<std::int64_t>());
        solved.outliers.non_finite = file.header.at("outliers").at("non_finite").get<std::int64_t>();
        solved.outliers.fireflies = file.header.at("outliers").at("fireflies").get<std::int64_t>();
        solved.frame_noise_factors = file.header.at("frame_noise_factors").get<std::vector<double>>();
        solved.frame_scale_factors = file.header.at("frame_scale_factors").get<std::vector<double>>();
        if (solved.frame_noise_factors.size() != static_cast<size_t>(frames) ||
            solved.frame_scale_factors.size() != static_cast<size_t>(frames))
            throw bad_input(path, "damaged solve file: its sizes do not agree");
        const nlohmann::json& repeating = file.header.at("repeating_noise");
        solved.repeating.measured = repeating.at("measured").get<bool>();
        solved.repeating.temporal = repeating.at("temporal").get<double>();
        solved.repeating.spatial = repeating.at("spatial").get<double>();
        solved.repeating.coarse = repeating.at("coarse").get<double>();
        solved.repeating.share = repeating.at("share").get<double>();
        solved.repeating.whiteness = repeating.at("whiteness").get<double>();
        solved.repeating.level = repeating.at("level").get<double>();
        solved.repeating.repeats = repeating.at("repeats").get<bool>();
        solved.repeating.frames = repeating.at("frames").get<std::vector<int>>();
        return solved;
    } catch (const nlohmann::json::exception& error) {
        throw bad_input(path, fmt::format("damaged stage file header: {}", error.what()));
    }
}

namespace {

// A row's bias posterior as floats: its slopes, then its offsets.
constexpr std::size_t kBiasFloatsPerRow = 2 * lowrank::kBiasBins;

std::vector<float> bias_floats(const std::vector<lowrank::BiasPosterior>& rows)
{
    std::vector<float> floats;
    floats.reserve(rows.size() * kBiasFloatsPerRow);
    for (const lowrank::BiasPosterior& row : rows) {
        floats.insert(floats.end(), row.slope.begin(), row.slope.end());
        floats.insert(floats.end(), row.offset.begin(), row.offset.end());
    }
    return floats;
}

std::vector<lowrank::BiasPosterior> bias_rows(const std::vector<float>& floats)
{
    std::vector<lowrank::BiasPosterior> rows(floats.size() / kBiasFloatsPerRow);
    for (std::size_t r = 0; r < rows.size(); ++r) {
        const float* row = floats.data() + r * kBiasFloatsPerRow;
        std::copy_n(row, lowrank::kBiasBins, rows[r].slope.begin());
        std::copy_n(row + lowrank::kBiasBins, lowrank::kBiasBins, rows[r].offset.begin());
    }
    return rows;
}

} // namespace

std::string modes_bytes(const ShotFingerprint& fingerprint, const StageBytes& solve, const std::string& surveys,
                        const denoise::ModeImages& band)
{
    nlohmann::ordered_json header = header_for(denoise::Stage::Modes, fingerprint, 0);
    header["solve"] = digest_of(solve.bytes);
    header["surveys"] = surveys;
    header["rows"] = {band.row_begin, band.row_end};
    header["residual_modes"] = band.residual_modes;
    header["output_modes"] = band.output_modes;
    header["gain_modes"] = band.gain_modes;
    header["patches"] = band.patches.size();
    Payload payload;
    for (const denoise::ModeImages::Patch& patch : band.patches) {
        payload.add(patch.frame);
        payload.add(static_cast<double>(patch.sample));
        payload.add(patch.value);
    }
    for (const std::vector<float>* values : {&band.residual, &band.output, &band.noise_variance, &band.gains})
        payload.add_floats(*values);
    payload.add_floats(bias_floats(band.bias));
    return stage_bytes(header, payload);
}

std::vector<denoise::ModeImages> read_modes(const std::vector<StageBytes>& inputs, const StageBytes& solve,
                                            const std::string& surveys, const ShotFingerprint& fingerprint, int width,
                                            int height, int channels)
{
    if (inputs.empty())
        throw usage_error("--stage write needs the modes files of the shot: --modes FILE...");
    const auto [files, bands] = read_row_files(
        inputs, denoise::Stage::Modes, fingerprint, height, "modes", &solve,
        [&](const std::string& path, const nlohmann::json& header, int begin, int end) {
            if (header.at("surveys").get<std::string>() != surveys)
                throw bad_input(path, "was made from other survey sums than the survey files given");
            const std::size_t samples = static_cast<std::size_t>(width) * channels * (end - begin);
            const std::size_t floats = samples * (header.at("residual_modes").get<std::size_t>() +
                                                  header.at("output_modes").get<std::size_t>() + 1) +
                                       samples / channels * header.at("gain_modes").get<std::size_t>() +
                                       static_cast<std::size_t>(end - begin) * kBiasFloatsPerRow;
            return header.value("floats", std::size_t(0)) == floats &&
                   header.at("doubles").get<std::size_t>() == 3 * header.at("patches").get<std::size_t>();
        });
    std::vector<denoise::ModeImages> shot;
    for (const RowBand& row_band : bands) {
        const StageFile& file = files[row_band.file];
        denoise::ModeImages band;
        band.row_begin = row_band.begin;
        band.row_end = row_band.end;
        band.residual_modes = file.header.at("residual_modes").get<int>();
        band.output_modes = file.header.at("output_modes").get<int>();
        band.gain_modes = file.header.at("gain_modes").get<int>();
        const std::size_t samples = static_cast<std::size_t>(width) * channels * (band.row_end - band.row_begin);
        PayloadReader payload = file.payload();
        band.patches.resize(file.header.at("patches").get<std::size_t>());
        for (denoise::ModeImages::Patch& patch : band.patches) {
            patch.frame = static_cast<int>(payload.next());
            patch.sample = static_cast<std::int64_t>(payload.next());
            patch.value = static_cast<float>(payload.next());
        }
        band.residual = payload.floats(samples * band.residual_modes);
        band.output = payload.floats(samples * band.output_modes);
        band.noise_variance = payload.floats(samples);
        band.gains = payload.floats(samples / channels * band.gain_modes);
        band.bias = bias_rows(
            payload.floats(static_cast<std::size_t>(band.row_end - band.row_begin) * kBiasFloatsPerRow));
        if (!shot.empty() && (band.residual_modes != shot.front().residual_modes ||
                              band.output_modes != shot.front().output_modes ||
                              band.gain_modes != shot.front().gain_modes))
            throw bad_input(file.path, "damaged modes file: its modes differ from the other files'");
        shot.push_back(std::move(band));
    }
    return shot;
}

std::string survey_bytes(const ShotFingerprint& fingerprint, const StageBytes& solve, const denoise::SurveyRows& survey)
{
    nlohmann::ordered_json header = header_for(denoise::Stage::Survey, fingerprint, 0);
    header["solve"] = digest_of(solve.bytes);
    header["rows"] = {survey.row_begin, survey.row_end};
    const std::size_t length = survey.sums.empty() ? 0 : survey.sums.front().size();
    header["survey_row_length"] = length;
    Payload payload;
    for (const std::vector<double>& row : survey.sums) {
        if (row.size() != length)
            throw internal_error("survey_bytes: survey rows of different lengths");
        for (double value : row)
            payload.add(value);
    }
    return stage_bytes(header, payload);
}

denoise::SurveyRows read_surveys(const std::vector<StageBytes>& inputs, const StageBytes& solve,
                                 const ShotFingerprint& fingerprint, int height)
{
    if (inputs.empty())
        throw usage_error("the modes and write stages need the survey files of the shot: --survey FILE...");
    std::optional<std::size_t> first_length;  // every file of a job surveys the same modes
    const auto [files, bands] = read_row_files(
        inputs, denoise::Stage::Survey, fingerprint, height, "survey", &solve,
        [&](const std::string&, const nlohmann::json& header, int begin, int end) {
            const std::size_t length = header.at("survey_row_length").get<std::size_t>();
            if (!first_length)
                first_length = length;
            const std::size_t rows = length == 0 ? 0 : static_cast<std::size_t>(end - begin);
            return header.at("doubles").get<std::size_t>() == rows * length && length == *first_length;
        });
    denoise::SurveyRows shot;
    shot.row_begin = 0;
    shot.row_end = height;
    for (const RowBand& band : bands) {
        const StageFile& file = files[band.file];
        const std::size_t length = file.header.at("survey_row_length").get<std::size_t>();
        if (length == 0)
            continue;  // no mode filter: nothing was surveyed
        PayloadReader payload = file.payload();
        for (int row = band.begin; row < band.end; ++row) {
            std::vector<double> sums(length);
            for (double& value : sums)
                value = payload.next();
            shot.sums.push_back(std::move(sums));
        }
    }
    return shot;
}

std::string survey_digest(const std::vector<std::vector<double>>& rows)
{
    std::string all;
    for (const std::vector<double>& row : rows)
        all.append(reinterpret_cast<const char*>(row.data()), row.size() * sizeof(double));
    return digest_of(all);
}

}  // namespace modestack::io
