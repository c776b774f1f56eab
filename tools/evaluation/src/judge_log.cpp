#include "swf/drivers/log_stereo_source.hpp"
#include "swf/evaluation/run_judge.hpp"
#include "swf/messages/checked_decode.hpp"

namespace swf::evaluation {

bool JudgeLogs(const std::vector<std::string>& paths, RunJudge* judge, LogTally* tally,
               std::string* error) {
  const auto add = [&](const drivers::LogEvent& event) {
    ++tally->events;
    judge->Add(event.channel, event.data.data(), event.data.size());
    if (event.channel == judge->Channels().hazard &&
        messages::CheckedDecode(event.data.data(), event.data.size(), &tally->last_hazard_map)
            .Ok()) {
      tally->has_hazard_map = true;
    }
    return true;
  };
  for (const std::string& path : paths) {
    if (!drivers::ForEachLogEvent(path, add, error)) return false;
  }
  return true;
}

}  // namespace swf::evaluation
