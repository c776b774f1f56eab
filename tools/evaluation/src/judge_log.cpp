#include "swf/drivers/log_stereo_source.hpp"
#include "swf/evaluation/run_judge.hpp"
#include "swf/messages/checked_decode.hpp"

namespace swf::evaluation {

bool JudgeLog(const std::string& path, RunJudge* judge, LogTally* tally, std::string* error) {
  drivers::LogReader reader;
  if (!reader.Open(path, error)) return false;
  drivers::LogEvent event;
  for (;;) {
    const int r = reader.Next(&event, error);
    if (r == 0) return true;
    if (r < 0) return false;
    ++tally->events;
    judge->Add(event.channel, event.data.data(), event.data.size());
    if (event.channel == judge->Channels().hazard &&
        messages::CheckedDecode(event.data.data(), event.data.size(), &tally->last_hazard_map)
            .Ok()) {
      tally->has_hazard_map = true;
    }
  }
}

}  // namespace swf::evaluation
