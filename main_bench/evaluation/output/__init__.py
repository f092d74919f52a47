"""What an evaluation writes and reads back: the record schemas (`records`), the results directory and its
`summary.json` (`results`), and the ledger of part-file hashes that makes tampering evident (`ledger`).
"""
