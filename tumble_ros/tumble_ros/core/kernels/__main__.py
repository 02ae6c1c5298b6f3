"""Print the layouts of the kernels' arrays: ``python -m tumble_ros.core.kernels``."""
from tumble_ros.core.kernels import BB, BK, BT, CF, describe, LI, LN, PR, ST

if __name__ == '__main__':
    print('\n\n'.join(describe(table) for table in (ST, PR, CF, BK, BT, BB, LI, LN)))
