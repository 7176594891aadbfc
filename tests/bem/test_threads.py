"""bem.threads.single_threaded_blas: same numbers, thread count restored."""

import numpy as np

from bem.threads import _setters, single_threaded_blas


def test_single_threaded_blas_gives_the_same_products_and_restores_the_thread_count():
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((300, 200)), rng.standard_normal((200, 30))
    with single_threaded_blas():
        inside = a @ b
        counts = [fn(1) for fn in _setters()]          # set to 1 inside the block
    assert all(n == 1 for n in counts)
    after = [fn(0) for fn in _setters()]               # 0 leaves the count, returns it
    for fn, n in zip(_setters(), after):
        fn(n)
    np.testing.assert_allclose(inside, a @ b, rtol=1e-13, atol=1e-13)
    assert all(n >= 1 for n in after)
