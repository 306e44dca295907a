"""The head behind the board's pins: the stages, the laser and the
photodiode, in a process of its own (`board-plant`, the simulated head's
world from `gonio_sim::plant`), so that the optics are the simulated
head's and nothing here reads the firmware's variables.

Output changes go to it as they happen, unanswered (buffered until the
next question); the home switches are asked for when the image reads
their port, and conversions when the ADC completes them. Times are the
board's cycles."""

import json
import subprocess


class Plant:
    def __init__(self, command):
        self.proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1 << 16)
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"{command[0]} did not start (exit {self.proc.wait()})")
        header = json.loads(line)
        self.outputs = set(header["outputs"])
        self.switches = header["switches"]
        self.photodiode = header["photodiode"]

    def output(self, cycle, pin, level):
        if pin in self.outputs:
            self.proc.stdin.write(f"p {cycle} {pin} {level}\n")

    def _ask(self, line):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        answer = self.proc.stdout.readline()
        if not answer:
            raise RuntimeError(f"board-plant ended (exit {self.proc.poll()})")
        return answer.strip()

    def switch_levels(self, cycle):
        """{pin: level} of the home switches' lines at `cycle`."""
        return dict(zip(self.switches, map(int, self._ask(f"s {cycle}").split())))

    def convert(self, n, start, step):
        """The codes (little-endian 16-bit bytes) of `n` conversions sampled
        at `start + k·step` cycles."""
        return bytes.fromhex(self._ask(f"c {n} {start!r} {step!r}"))


    def close(self):
        self.proc.stdin.close()
        self.proc.wait(timeout=5)
