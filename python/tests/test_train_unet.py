"""day2night.train.unet: the release's UNet (utils/unet.py of SamsungLabs/day-to-night),
checked layer by layer and by its parameter count, computed here from that architecture."""

import pytest
from conftest import need_torch


def release_parameter_count(cin=3, cout=3, f=32):
    """The release's UNet, counted from its description: a level is conv3x3 (no bias) +
    BatchNorm (weight, bias) twice; up-convolutions are 2x2 transposed convs with bias;
    the head is a 1x1 conv with bias."""
    def level(a, b):
        return a * b * 9 + 2 * b + b * b * 9 + 2 * b

    def up(a, b):
        return a * b * 4 + b

    down = level(cin, f) + level(f, 2 * f) + level(2 * f, 4 * f) + level(4 * f, 8 * f)
    bottleneck = level(8 * f, 16 * f)
    ups = (up(16 * f, 8 * f) + level(16 * f, 8 * f) + up(8 * f, 4 * f) + level(8 * f, 4 * f)
           + up(4 * f, 2 * f) + level(4 * f, 2 * f) + up(2 * f, f) + level(2 * f, f))
    return down + bottleneck + ups + f * cout + cout


def test_parameter_count_is_the_releases():
    need_torch()
    from day2night.train.unet import UNet, parameter_count
    # UNet(in_channels=3, out_channels=3, init_features=32), as train.py/test.py build it
    assert release_parameter_count() == 7_763_107
    assert parameter_count(UNet(3, 3, 32)) == 7_763_107
    # the widely quoted count of the same UNet with one output channel
    assert parameter_count(UNet(3, 1, 32)) == release_parameter_count(3, 1, 32) == 7_763_041
    assert parameter_count(UNet(3, 3, 4)) == release_parameter_count(3, 3, 4)


def test_layers_names_and_shapes():
    torch = need_torch()
    from day2night.train.unet import UNet
    m = UNet(3, 3, 32)
    sd = m.state_dict()
    assert sd["encoder1.enc1conv1.weight"].shape == (32, 3, 3, 3)
    assert "encoder1.enc1conv1.bias" not in sd
    assert sd["encoder1.enc1norm1.running_mean"].shape == (32,)
    assert sd["bottleneck.bottleneckconv2.weight"].shape == (512, 512, 3, 3)
    assert sd["upconv4.weight"].shape == (512, 256, 2, 2)
    assert sd["upconv4.bias"].shape == (256,)
    assert sd["decoder4.dec4conv1.weight"].shape == (256, 512, 3, 3)
    assert sd["decoder1.dec1conv2.weight"].shape == (32, 32, 3, 3)
    assert sd["conv.weight"].shape == (3, 32, 1, 1) and sd["conv.bias"].shape == (3,)
    convs = [k for k in sd if k.endswith(".weight") and sd[k].dim() == 4]
    # 9 levels x 2 convs + 4 up-convs + the head
    assert len(convs) == 9 * 2 + 4 + 1
    x = torch.rand(2, 3, 32, 48)
    with torch.no_grad():
        y = m.eval()(x)
    assert y.shape == (2, 3, 32, 48)
    assert float(y.min()) > 0 and float(y.max()) < 1  # sigmoid


def test_bad_width_is_refused():
    need_torch()
    from day2night.train.unet import UNet
    with pytest.raises(ValueError, match="init_features"):
        UNet(3, 3, 0)
