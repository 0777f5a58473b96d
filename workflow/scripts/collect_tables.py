import pandas as pd

from thermaxis.runner import run_script, write_csv

ORDER = {
    "metrics": ["fold", "approach", "algorithm", "target"],
    "coefficients": ["fold", "approach", "algorithm", "target", "position_mm", "temperature", "term"],
    "kb": ["fold", "approach", "algorithm", "target", "measurement"],
    "errors": ["fold", "approach", "algorithm", "measurement", "position_mm"],
    "selection": ["fold", "target", "position_mm", "cluster", "sensor"],
}


def main(snakemake):
    for name, keys in ORDER.items():
        frames = [pd.read_csv(p) for p in snakemake.input[name]]
        frame = pd.concat(frames, ignore_index=True).sort_values(keys, kind="stable", ignore_index=True)
        write_csv(frame, snakemake.output[name], float_format="%.6f")


run_script(main, snakemake)
