"""Issue 33: Python calls from several threads at once. Eight threads run ctid.srivc,
ctid.identify, ctid.oma and the document readers and writers on different small seeded records,
each thread its jobs in its own seeded order, twice over; every result must be the serial
run's bit for bit (its JSON document, which carries every number to 17 digits) and nothing may
crash. srivc and identify release the GIL (py::gil_scoped_release), so their C++ runs
really overlap."""

import concurrent.futures
import pathlib
import random
import threading

import numpy as np

import ctid

H = 0.05
THREADS = 8


def _record(seed):
    g = ctid.TransferFunction([4.0 + 0.1 * seed], [4.0, 0.8, 1.0])
    u = ctid.white_noise(600, 1.0, 100 + seed)
    y = ctid.simulate(g, u, H) + ctid.white_noise(600, 0.02, 200 + seed)
    return ctid.SampledData(H, u, y)


def _outputs(seed, samples=3000):
    """Two channels of a seeded, lightly damped pair of modes driven by white noise."""
    rng = np.random.default_rng(seed)
    a = np.array([[1.9 * np.cos(0.3), -0.95], [1.0, 0.0]])
    x = np.zeros(2)
    y = np.empty((samples, 2))
    for k in range(samples):
        x = a @ x + np.array([rng.standard_normal(), 0.0])
        y[k] = [x[0] + 0.05 * rng.standard_normal(), x[0] - x[1]]
    return y


def _jobs(folder):
    """name -> a call returning text to compare; every call on its own data and files."""
    folder = pathlib.Path(folder)
    jobs = {}
    for seed in range(4):
        data = _record(seed)
        jobs[f"srivc {seed}"] = lambda data=data: ctid.result_to_json(
            ctid.srivc(data, ctid.SubmodelOrder(2, 0), max_iterations=30))
        jobs[f"identify {seed}"] = lambda data=data: ctid.result_to_json(
            ctid.identify(data, ctid.ModelStructure.modes(1)).estimate)
        csv = folder / f"d{seed}.csv"
        ctid.write_csv(csv, data)
        document = folder / f"r{seed}.json"
        ctid.write_result(document, ctid.srivc(data, ctid.SubmodelOrder(2, 0)))
        jobs[f"read {seed}"] = lambda csv=csv, document=document: (
            ctid.read_csv(csv).output.tobytes().hex() + "\n" +
            ctid.result_to_json(ctid.read_result(document)))
    for seed in range(2):
        y = _outputs(seed)
        jobs[f"oma {seed}"] = lambda y=y: ctid.result_to_json(
            ctid.oma(y, H, max_order=8, block_rows=10, uncertainty_blocks=0))
    return jobs


def test_calls_from_eight_threads_equal_the_serial_calls(tmp_path):
    jobs = _jobs(tmp_path)
    serial = {name: call() for name, call in jobs.items()}
    assert len(set(serial.values())) == len(serial)  # different data, different results
    start = threading.Barrier(THREADS)

    def worker(index):
        order = list(jobs) * 2
        random.Random(index).shuffle(order)
        start.wait()  # every thread starts at once
        return [(name, jobs[name]()) for name in order]

    with concurrent.futures.ThreadPoolExecutor(max_workers=THREADS) as pool:
        results = list(pool.map(worker, range(THREADS)))
    assert sum(len(r) for r in results) == THREADS * 2 * len(jobs)
    for per_thread in results:
        for name, text in per_thread:
            assert text == serial[name], name
