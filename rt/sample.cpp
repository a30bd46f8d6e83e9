#include "rt/sample.hpp"

namespace rigctl {

namespace {
int find_channel(const std::vector<ChannelInfo>& channels, const std::string& name) {
  for (std::size_t i = 0; i < channels.size(); ++i) {
    if (channels[i].name == name) return static_cast<int>(i);
  }
  return -1;
}
}  // namespace

int ChannelLayout::input_index(const std::string& name) const { return find_channel(inputs, name); }
int ChannelLayout::output_index(const std::string& name) const { return find_channel(outputs, name); }

}  // namespace rigctl
