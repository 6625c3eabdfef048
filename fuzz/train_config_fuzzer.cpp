// libFuzzer target: training configs (train/vae_config.h, translate/translation_config.h) from YAML
// text: the task, then the reader for it, with an override taken from the first line
// ("a.b=value") as `retarget train --set` applies it.
#include <string>

#include "core/config.h"
#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "train/train_config.h"
#include "train/vae_config.h"
#include "translate/translation_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(retarget::fuzz::bytes(data, size));
  try {
    retarget::ConfigNode root = retarget::ConfigNode::parse(text, "train.yaml");
    const size_t newline = text.find('\n');
    if (newline != std::string::npos && text.find('=') < newline) root.apply_override(text.substr(0, newline));
    const std::string task = retarget::config_task(root);
    if (task == "vae")
      (void)retarget::to_yaml(retarget::read_vae_train_config(root));
    else
      (void)retarget::to_yaml(retarget::read_translation_train_config(root));
  } catch (const retarget::Error&) {
  }
  return 0;
}
