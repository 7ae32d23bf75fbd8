"""Element kernels: shape functions, quadrature, reference geometry, layer kernels."""
