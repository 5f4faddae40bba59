// Placeholder translation unit; the TetGen adapter is being written.
namespace normalflow::detail { int tetgen_adapter_placeholder = 0; }
