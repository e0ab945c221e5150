"""What each part of 2D-RL contributes on the paper's task: see :mod:`twodrl_bench.ablation`.

python scripts/ablation.py --out runs/ablation                      # 5 arms x 10 seeds, 50 paper epochs
python scripts/ablation.py --out runs/ablation_open --env NomadOfficeOpen-v0
python scripts/ablation.py --out /tmp/look --seeds 0 --epochs 2 -K 50 -M 20   # a quick look
"""

from twodrl_bench.ablation import main

if __name__ == "__main__":
    main()
