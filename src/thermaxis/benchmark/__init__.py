"""Published results on public data, reproduced under their authors' own protocol.

A benchmark names a public record (through an import mapping), the protocol its
authors evaluated with and the numbers they published; thermaxis's models are run
under the same protocol, every choice made on the training part alone, and placed
beside the published figures.
"""
