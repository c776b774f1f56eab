// A QEMU TCG plugin that counts the guest instructions each stage of the flight process
// executes (stage_profile.py loads it into qemu-aarch64 and, to validate it against callgrind,
// into qemu-x86_64).
//
//   qemu-aarch64 -plugin libswf_stage_count.so,out=F,stage=NAME:PREFIX,stage=... BIN ARGS
//
// Each translated block is classified once, by the symbol of its first instruction (the
// emulator's lookup in the binary's symbol table): a block of a function whose mangled name
// starts with a stage's PREFIX enters that stage. The stage functions' caller is a stage too
// (e.g. "loop": FlightLoop::Cycle), so that when a stage function returns, the next block (in
// its caller) leaves it. Every executed block adds its instruction count to the current stage of
// its thread (each guest thread is a vCPU; a thread starts in "other"). A stage's count is thus
// the stage function and everything it calls, as callgrind's inclusive cost of that function.
// At exit the counts are written to F as JSON.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "qemu_plugin_api.hpp"

namespace {

constexpr int kMaxThreads = 256;
constexpr int kMaxStages = 16;  // stage 0 is "other": everything outside the named stages
constexpr int kNoTransition = -1;

struct Prefix {
  std::string text;
  int stage = 0;
};

struct BlockInfo {
  std::uint64_t instructions = 0;
  int transition = kNoTransition;
};

struct Thread {
  int stage = 0;
  std::uint64_t count[kMaxStages] = {};
};

std::vector<std::string> g_stage_names{"other"};
std::vector<Prefix> g_prefixes;
std::string g_out_path;
Thread g_threads[kMaxThreads];
std::uint64_t g_threads_overflowed = 0;  // blocks of vCPUs beyond kMaxThreads (reported)

int StageIndex(const std::string& name) {
  for (std::size_t i = 0; i < g_stage_names.size(); ++i) {
    if (g_stage_names[i] == name) return static_cast<int>(i);
  }
  if (static_cast<int>(g_stage_names.size()) >= kMaxStages) return -1;
  g_stage_names.push_back(name);
  return static_cast<int>(g_stage_names.size()) - 1;
}

int TransitionOf(const char* symbol) {
  if (symbol == nullptr) return kNoTransition;
  for (const Prefix& p : g_prefixes) {
    if (std::strncmp(symbol, p.text.c_str(), p.text.size()) == 0) return p.stage;
  }
  return kNoTransition;
}

void OnBlockExecuted(unsigned int vcpu_index, void* userdata) {
  const auto* block = static_cast<const BlockInfo*>(userdata);
  if (vcpu_index >= static_cast<unsigned int>(kMaxThreads)) {
    ++g_threads_overflowed;
    return;
  }
  Thread& t = g_threads[vcpu_index];
  if (block->transition != kNoTransition) t.stage = block->transition;
  t.count[t.stage] += block->instructions;
}

void OnBlockTranslated(qemu_plugin_id_t /*id*/, qemu_plugin_tb* tb) {
  const std::size_t n = qemu_plugin_tb_n_insns(tb);
  if (n == 0) return;
  // Blocks are retranslated rarely; their records live as long as the emulator.
  auto* block =
      new BlockInfo{n, TransitionOf(qemu_plugin_insn_symbol(qemu_plugin_tb_get_insn(tb, 0)))};
  qemu_plugin_register_vcpu_tb_exec_cb(tb, OnBlockExecuted, QEMU_PLUGIN_CB_NO_REGS, block);
}

void WriteCounts(qemu_plugin_id_t /*id*/, void* /*userdata*/) {
  std::FILE* f = std::fopen(g_out_path.c_str(), "w");
  if (f == nullptr) {
    qemu_plugin_outs("swf stage counter: cannot write its output file\n");
    return;
  }
  std::uint64_t total[kMaxStages] = {};
  std::fprintf(f, "{\"threads\": [");
  bool first = true;
  for (int v = 0; v < kMaxThreads; ++v) {
    std::uint64_t sum = 0;
    for (int s = 0; s < kMaxStages; ++s) sum += g_threads[v].count[s];
    if (sum == 0) continue;
    std::fprintf(f, "%s{\"vcpu\": %d", first ? "" : ", ", v);
    for (std::size_t s = 0; s < g_stage_names.size(); ++s) {
      std::fprintf(f, ", \"%s\": %llu", g_stage_names[s].c_str(),
                   static_cast<unsigned long long>(g_threads[v].count[s]));
      total[s] += g_threads[v].count[s];
    }
    std::fprintf(f, "}");
    first = false;
  }
  std::fprintf(f, "], \"stages\": {");
  std::uint64_t all = 0;
  for (std::size_t s = 0; s < g_stage_names.size(); ++s) {
    std::fprintf(f, "%s\"%s\": %llu", s == 0 ? "" : ", ", g_stage_names[s].c_str(),
                 static_cast<unsigned long long>(total[s]));
    all += total[s];
  }
  std::fprintf(f, "}, \"total\": %llu, \"blocks_of_untracked_threads\": %llu}\n",
               static_cast<unsigned long long>(all),
               static_cast<unsigned long long>(g_threads_overflowed));
  std::fclose(f);
}

// stage=NAME:PREFIX or out=PATH; false for anything else.
bool ParseArgument(const std::string& arg) {
  if (arg.rfind("out=", 0) == 0) {
    g_out_path = arg.substr(4);
    return !g_out_path.empty();
  }
  if (arg.rfind("stage=", 0) == 0) {
    const std::size_t colon = arg.find(':', 6);
    if (colon == std::string::npos || colon == 6 || colon + 1 == arg.size()) return false;
    const int stage = StageIndex(arg.substr(6, colon - 6));
    if (stage < 0) return false;
    g_prefixes.push_back(Prefix{arg.substr(colon + 1), stage});
    return true;
  }
  return false;
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) int qemu_plugin_version = 1;  // NOLINT: QEMU's name

// NOLINTNEXTLINE(readability-identifier-naming): the entry point QEMU looks up by name
__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id,
                                                               const qemu_info_t* /*info*/,
                                                               int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    if (!ParseArgument(argv[i])) {
      std::fprintf(stderr, "swf stage counter: bad argument '%s' (stage=NAME:PREFIX, out=PATH)\n",
                   argv[i]);
      return -1;
    }
  }
  if (g_out_path.empty()) {
    std::fprintf(stderr, "swf stage counter: out=PATH is required\n");
    return -1;
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, OnBlockTranslated);
  qemu_plugin_register_atexit_cb(id, WriteCounts, nullptr);
  return 0;
}

}  // extern "C"
