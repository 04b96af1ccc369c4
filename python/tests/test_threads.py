"""The GIL is released around the C++ work: while one thread is inside a call, another runs Python.

No clock: each extension counts the threads inside a GIL-free section (_calls_in_progress, counted
only while the GIL is released), and the main thread, which needs the GIL to read the count, can
only ever see it above zero if the worker really let go of the GIL. Without the release this would
fail (the worker's loop ends and the count was never seen), not hang.
"""

import threading

import numpy as np

import stereodet
from stereodet import kitti, stereo


def seen_inside(extension, work, calls=200):
    """Runs work() up to `calls` times in a thread; True once the main thread sees it in C++."""
    stop = threading.Event()

    def worker():
        for _ in range(calls):
            if stop.is_set():
                return
            work()

    thread = threading.Thread(target=worker)
    thread.start()
    seen = False
    while thread.is_alive() and not seen:
        seen = extension._calls_in_progress() > 0
    stop.set()
    thread.join()
    return seen


def test_nothing_is_inside_when_idle():
    assert stereodet._core._calls_in_progress() == 0
    assert stereo._stereo._calls_in_progress() == 0


def test_stereo_releases_the_gil():
    rng = np.random.default_rng(0)
    left = rng.integers(0, 256, (375, 1242, 3), dtype=np.uint8)
    right = np.roll(left, -10, axis=1)
    assert seen_inside(stereo._stereo, lambda: stereo.disparity(left, right))
    assert stereo._stereo._calls_in_progress() == 0


def test_kitti_parsing_releases_the_gil():
    line = "Car 0.00 0 1.85 387.63 181.54 423.81 203.12 1.67 1.87 3.69 -16.53 2.39 58.49 1.57\n"
    text = line * 20000
    assert seen_inside(stereodet._core, lambda: kitti.parse_objects(text))


def test_evaluation_releases_the_gil():
    from conftest import random_annos

    gt, dt = random_annos(400, seed=3)
    assert seen_inside(stereodet._core, lambda: stereodet.evaluate(gt, dt, num_threads=1))


def test_two_threads_evaluate_at_once_to_the_same_numbers():
    from conftest import random_annos

    gt, dt = random_annos(100, seed=4)
    expected = stereodet.evaluate(gt, dt).to_dict()["results"]
    results = [None, None]

    def run(i):
        results[i] = stereodet.evaluate(gt, dt, num_threads=1).to_dict()["results"]

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results[0] == expected and results[1] == expected
