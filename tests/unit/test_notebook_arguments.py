"""The report runner's JSON arguments: on the command line, or on standard input."""

import io
import json

from thermaxis.reports.notebooks import json_argument


def test_a_json_value_is_read_from_the_command_line_or_from_stdin():
    assert json_argument('{"runs": ["R1"]}') == {"runs": ["R1"]}
    # 300 KiB of pages: more than Linux's 128 KiB cap on one argument, fine on stdin.
    pages = [{"executed": f"results/x/reports/model_S{i:04d}.ipynb", "parameters": {"pad": "x" * 300}}
             for i in range(1000)]  # fmt: skip
    text = json.dumps(pages)
    assert len(text) > 128 * 1024
    assert json_argument("-", stdin=io.StringIO(text)) == pages
