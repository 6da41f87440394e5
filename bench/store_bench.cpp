// store_bench.cpp — the store's claim throughput (issue 12): N empty jobs are submitted, then T
// threads claim them as fast as they can, each claim followed by the job's end (finish_job under
// its lease), as workers do; then T threads read job status (find_job). Any backend open_store
// opens: a SQLite file or a PostgreSQL URI. Checks that every job was claimed exactly once.
//
//   build/release/bench/store_bench URL [JOBS=5000] [THREADS=16]
//   (bench/postgres_bench.py runs it on a private PostgreSQL cluster and on SQLite)
#include "store/store.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
using namespace manipid::server;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: store_bench URL [JOBS] [THREADS]\n");
    return 2;
  }
  const std::string url = argv[1];
  const int jobs = argc > 2 ? std::atoi(argv[2]) : 5000;
  const int threads = argc > 3 ? std::atoi(argv[3]) : 16;
  store::StoreOptions options;
  options.connections = static_cast<std::size_t>(threads) + 1;
  const auto store = store::open_store(url, options);

  store::NewJob job;
  job.kind = manipid::api::JobKind::identification;
  job.request = "{}";
  std::vector<std::string> ids;
  auto started = Clock::now();
  for (int i = 0; i < jobs; ++i) ids.push_back(store->submit_job(job, std::nullopt, 0).job.id);
  const double submit_seconds = seconds_since(started);

  store::JobEnd succeeded;
  succeeded.state = manipid::api::JobState::succeeded;
  succeeded.result = "{}";
  std::mutex mutex;
  std::multiset<std::string> claimed;
  std::vector<std::thread> claimers;
  std::atomic<int> lost{0};
  started = Clock::now();
  for (int t = 0; t < threads; ++t) {
    claimers.emplace_back([&, t] {
      const std::string owner = "bench:" + std::to_string(t);
      std::vector<std::string> mine;
      while (auto next = store->claim_next_job(owner, std::chrono::seconds(30))) {
        const store::Lease lease{next->id, next->worker, next->attempts};
        if (!store->finish_job(lease, succeeded)) ++lost;
        mine.push_back(next->id);
      }
      std::lock_guard lock(mutex);
      claimed.insert(mine.begin(), mine.end());
    });
  }
  for (auto& thread : claimers) thread.join();
  const double claim_seconds = seconds_since(started);

  std::atomic<long> reads{0};
  std::vector<std::thread> readers;
  started = Clock::now();
  const auto read_until = started + std::chrono::seconds(3);
  for (int t = 0; t < threads; ++t) {
    readers.emplace_back([&, t] {
      for (std::size_t i = static_cast<std::size_t>(t); Clock::now() < read_until; i += static_cast<std::size_t>(threads)) {
        if (store->find_job(manipid::api::all_owners, ids[i % ids.size()])) ++reads;
      }
    });
  }
  for (auto& thread : readers) thread.join();
  const double read_seconds = seconds_since(started);

  const bool each_once = claimed.size() == ids.size() && std::set<std::string>(claimed.begin(), claimed.end()).size() == ids.size();
  std::printf("%s: %d jobs submitted in %.2f s (%.0f/s); %d threads claimed and ended them in %.2f s: %.0f claims/s "
              "(each once: %s, lost leases %d); status reads: %.0f/s\n",
              store::display_name(url).c_str(), jobs, submit_seconds, jobs / submit_seconds, threads, claim_seconds,
              jobs / claim_seconds, each_once ? "yes" : "NO", lost.load(), static_cast<double>(reads) / read_seconds);
  return each_once && lost == 0 ? 0 : 1;
}
