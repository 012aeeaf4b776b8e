// libFuzzer target: a TetGen .node/.ele pair, loaded with sh_mesh_load through either file and
// checked as fuzz_check.hpp says. One input holds both files: the .node text, a line ".ele", then
// the .ele text (a ".ele" line is never valid .node content, so the split hides nothing the reader
// could accept). Without that line the whole input is the .node and the .ele is empty.
// Seeds: corpus/tetgen/.
#include "fuzz_check.hpp"

namespace {

constexpr std::string_view kSplit = "\n.ele\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace softhap_fuzz;
    const std::string_view input = as_text(data, size);
    const size_t split = input.find(kSplit);
    const File node = write_input("input.node", input.substr(0, split));
    const File ele = write_input("input.ele", split == std::string_view::npos ? std::string_view()
                                                                              : input.substr(split + kSplit.size()));
    // Through the .node the .ele is read second, through the .ele first: both orders.
    check_load(node.path, {node, ele});
    check_load(ele.path, {node, ele});
    return 0;
}
