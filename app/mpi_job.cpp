#include "app/mpi_job.h"

#include "core/common/error.h"

#include <fmt/format.h>
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <new>

namespace modestack::app {
namespace {

// MPI_Init for the lifetime of the job; MPI_Finalize after.
class MpiSession {
public:
    MpiSession()
    {
        MPI_Init(nullptr, nullptr);
        MPI_Comm_rank(MPI_COMM_WORLD, &m_rank);
        MPI_Comm_size(MPI_COMM_WORLD, &m_size);
    }
    ~MpiSession() { MPI_Finalize(); }
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;

    int rank() const { return m_rank; }
    int size() const { return m_size; }

    /// At rank 0: every rank's `mine`, in rank order (empty elsewhere).
    std::vector<io::StageBytes> gather(const std::string& mine) const
    {
        int length = static_cast<int>(mine.size());
        std::vector<int> lengths(m_size), offsets;
        MPI_Gather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
        std::string all;
        if (m_rank == 0)
            all.resize(offsets_of(lengths, "the ranks' statistics exceed 2 GB: use fewer ranks", offsets));
        MPI_Gatherv(mine.data(), length, MPI_BYTE, all.data(), lengths.data(), offsets.data(), MPI_BYTE, 0,
                    MPI_COMM_WORLD);
        return m_rank == 0 ? split(all, lengths, offsets, "statistics") : std::vector<io::StageBytes>{};
    }

    /// Every rank's `mine` at every rank, in rank order (`what` names them in errors).
    std::vector<io::StageBytes> all_gather(const std::string& mine, const std::string& what) const
    {
        int length = static_cast<int>(mine.size());
        std::vector<int> lengths(m_size), offsets;
        MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD);
        std::string all(offsets_of(lengths,
                                   fmt::format("the ranks' {} exceed 2 GB: use the farm stages (--stage) with files",
                                               what),
                                   offsets),
                        '\0');
        MPI_Allgatherv(mine.data(), length, MPI_BYTE, all.data(), lengths.data(), offsets.data(), MPI_BYTE,
                       MPI_COMM_WORLD);
        return split(all, lengths, offsets, what);
    }

    /// Rank 0's `bytes` at every rank.
    std::string broadcast(std::string bytes) const
    {
        int length = static_cast<int>(bytes.size());
        MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
        bytes.resize(static_cast<size_t>(length));
        MPI_Bcast(bytes.data(), length, MPI_BYTE, 0, MPI_COMM_WORLD);
        return bytes;
    }

    [[noreturn]] void abort(const std::string& message, int code) const
    {
        std::fprintf(stderr, "modestack: rank %d of %d: %s\n", m_rank, m_size, message.c_str());
        std::fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, code);
        std::_Exit(code);  // MPI_Abort does not return; in case it does
    }

private:
    // Where each rank's bytes start in a gathered buffer (into `offsets`); returns
    // their total. MPI counts bytes in int: beyond 2 GB the job fails with `too_large`.
    static std::size_t offsets_of(const std::vector<int>& lengths, const std::string& too_large,
                                  std::vector<int>& offsets)
    {
        long long total = 0;
        offsets.clear();
        for (int length : lengths) {
            offsets.push_back(static_cast<int>(total));
            total += length;
        }
        if (total > 2'000'000'000)
            throw bad_input("mpirun", too_large);
        return static_cast<std::size_t>(total);
    }

    // Each rank's non-empty part of a gathered buffer, named "the <what> of rank r".
    static std::vector<io::StageBytes> split(const std::string& all, const std::vector<int>& lengths,
                                         const std::vector<int>& offsets, const std::string& what)
    {
        std::vector<io::StageBytes> parts;
        for (std::size_t r = 0; r < lengths.size(); ++r)
            if (lengths[r] > 0)
                parts.push_back({fmt::format("the {} of rank {}", what, r), all.substr(offsets[r], lengths[r])});
        return parts;
    }

    int m_rank = 0;
    int m_size = 1;
};

}  // namespace

bool started_by_mpirun()
{
    for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
        if (const char* value = std::getenv(name); value && std::atoi(value) > 1)
            return true;
    return false;
}

int run_mpi_denoise(const std::string& frames, const RunStage& run_stage)
{
    MpiSession mpi;
    const bool lead = mpi.rank() == 0;
    const std::string share = fmt::format("{}/{}", mpi.rank() + 1, mpi.size());
    try {
        // Each stage's task gets its input files and leaves its output in memory.
        const auto stage_of = [&](const char* name, const std::string& rows) {
            StageOptions options;
            options.stage = name;
            options.rows = rows;
            options.in_memory = std::make_shared<StageFilesInMemory>();
            return options;
        };
        StageOptions stats = stage_of("stats", share);
        if (int code = run_stage(stats, frames, lead); code != 0)
            mpi.abort("the statistics stage failed", code);
        const std::vector<io::StageBytes> gathered = mpi.gather(stats.in_memory->output);

        std::string solved;
        if (lead) {
            StageOptions solve = stage_of("solve", "");
            solve.in_memory->stats = gathered;
            if (int code = run_stage(solve, frames, false); code != 0)
                mpi.abort("the solve stage failed", code);
            solved = std::move(solve.in_memory->output);
        }
        const io::StageBytes solve_file{"the solve of rank 0", mpi.broadcast(std::move(solved))};

        StageOptions survey = stage_of("survey", share);
        survey.in_memory->solve = solve_file;
        if (int code = run_stage(survey, frames, lead); code != 0)
            mpi.abort("the survey stage failed", code);
        const std::vector<io::StageBytes> all_surveys = mpi.all_gather(survey.in_memory->output, "survey");

        StageOptions modes = stage_of("modes", share);
        modes.in_memory->solve = solve_file;
        modes.in_memory->survey = all_surveys;
        if (int code = run_stage(modes, frames, lead); code != 0)
            mpi.abort("the modes stage failed", code);
        std::vector<io::StageBytes> all_modes = mpi.all_gather(modes.in_memory->output, "modes");

        StageOptions write = stage_of("write", "");
        write.in_memory->solve = solve_file;
        write.in_memory->survey = all_surveys;
        write.in_memory->modes = std::move(all_modes);
        return run_stage(write, share, lead);
    } catch (const Error& error) {
        mpi.abort(error.what(), exit_code(error.kind()));
    } catch (const std::bad_alloc&) {
        mpi.abort("out of memory (try a smaller --max-memory)", exit_code(ErrorKind::BadInput));
    } catch (const std::exception& error) {
        mpi.abort(std::string("internal error: ") + error.what(), exit_code(ErrorKind::Internal));
    }
}

}  // namespace modestack::app
