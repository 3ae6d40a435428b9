#include "server/request_queue.h"

namespace nephele {

bool RequestQueue::push(Job job) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || jobs_.size() >= limit_) return false;
    jobs_.push_back(std::move(job));
  }
  cv_.notify_one();
  return true;
}

void RequestQueue::clientGone(std::int64_t client) {
  {
    std::lock_guard lock(mutex_);
    gone_.push_back(client);
  }
  cv_.notify_one();
}

bool RequestQueue::stop() {
  bool was = false;
  {
    std::lock_guard lock(mutex_);
    was = stopping_;
    stopping_ = true;
  }
  cv_.notify_all();
  return was;
}

bool RequestQueue::stopping() const {
  std::lock_guard lock(mutex_);
  return stopping_;
}

std::size_t RequestQueue::depth() const {
  std::lock_guard lock(mutex_);
  return jobs_.size();
}

RequestQueue::Taken RequestQueue::wait(std::chrono::steady_clock::time_point until) {
  Taken taken;
  std::unique_lock lock(mutex_);
  cv_.wait_until(lock, until, [&] { return stopping_ || !jobs_.empty() || !gone_.empty(); });
  taken.jobs.swap(jobs_);
  taken.gone.swap(gone_);
  taken.stopping = stopping_;
  return taken;
}

}  // namespace nephele
