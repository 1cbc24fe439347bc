"""warprt.torch: renders as torch tensors, differentiable through Renderer.backward. Not tests/torch: a package of
that name here would be imported as the top-level `torch` (pytest puts tests/ on sys.path) and hide PyTorch."""
