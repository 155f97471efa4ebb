"""The night ISP network of the paper (Sec. 4.1) and of the authors' release (utils/unet.py):
a 4-level UNet, written here from its description.

- Each level: two 3x3 convolutions without bias (padding 1), each followed by BatchNorm and
  ReLU. Widths f, 2f, 4f, 8f on the way down, 16f at the bottleneck (f = ``init_features``,
  32 in the paper: 32, 64, 128, 256, 512).
- Down: 2x2 max-pool, stride 2. Up: 2x2 transposed convolution with stride 2 (with bias),
  halving the width, concatenated with the encoder's output of the same level (upsampled
  first, skip second), then the level's two convolutions.
- Head: a 1x1 convolution (with bias) to ``out_channels``, then a sigmoid.

The module names (encoder1..4, bottleneck, upconv4..1, decoder4..1, conv; inside a level
``<level>conv1``, ``<level>norm1``, ...) follow the release's, so a state dict saved by the
release's training loads into this class (``UNet.load_state_dict``).
"""

from collections import OrderedDict

from ._torch import Module, torch


def _level(cin, cout, name):
    nn = torch.nn
    return nn.Sequential(OrderedDict([
        (f"{name}conv1", nn.Conv2d(cin, cout, kernel_size=3, padding=1, bias=False)),
        (f"{name}norm1", nn.BatchNorm2d(cout)),
        (f"{name}relu1", nn.ReLU(inplace=True)),
        (f"{name}conv2", nn.Conv2d(cout, cout, kernel_size=3, padding=1, bias=False)),
        (f"{name}norm2", nn.BatchNorm2d(cout)),
        (f"{name}relu2", nn.ReLU(inplace=True)),
    ]))


class UNet(Module):
    """UNet(in_channels=3, out_channels=3, init_features=32): the paper's night ISP. Input
    N x in_channels x H x W with H and W multiples of 16 (four 2x poolings); output
    N x out_channels x H x W in (0, 1)."""

    #: Spatial size the input must be a multiple of.
    MULTIPLE = 16

    def __init__(self, in_channels=3, out_channels=3, init_features=32):
        super().__init__()
        nn = torch.nn
        f = int(init_features)
        if f < 1:
            raise ValueError(f"init_features {init_features!r} must be a positive integer")
        self.in_channels, self.out_channels, self.init_features = in_channels, out_channels, f
        self.encoder1 = _level(in_channels, f, "enc1")
        self.pool1 = nn.MaxPool2d(kernel_size=2, stride=2)
        self.encoder2 = _level(f, 2 * f, "enc2")
        self.pool2 = nn.MaxPool2d(kernel_size=2, stride=2)
        self.encoder3 = _level(2 * f, 4 * f, "enc3")
        self.pool3 = nn.MaxPool2d(kernel_size=2, stride=2)
        self.encoder4 = _level(4 * f, 8 * f, "enc4")
        self.pool4 = nn.MaxPool2d(kernel_size=2, stride=2)
        self.bottleneck = _level(8 * f, 16 * f, "bottleneck")
        self.upconv4 = nn.ConvTranspose2d(16 * f, 8 * f, kernel_size=2, stride=2)
        self.decoder4 = _level(16 * f, 8 * f, "dec4")
        self.upconv3 = nn.ConvTranspose2d(8 * f, 4 * f, kernel_size=2, stride=2)
        self.decoder3 = _level(8 * f, 4 * f, "dec3")
        self.upconv2 = nn.ConvTranspose2d(4 * f, 2 * f, kernel_size=2, stride=2)
        self.decoder2 = _level(4 * f, 2 * f, "dec2")
        self.upconv1 = nn.ConvTranspose2d(2 * f, f, kernel_size=2, stride=2)
        self.decoder1 = _level(2 * f, f, "dec1")
        self.conv = nn.Conv2d(f, out_channels, kernel_size=1)

    def forward(self, x):
        e1 = self.encoder1(x)
        e2 = self.encoder2(self.pool1(e1))
        e3 = self.encoder3(self.pool2(e2))
        e4 = self.encoder4(self.pool3(e3))
        b = self.bottleneck(self.pool4(e4))
        d4 = self.decoder4(torch.cat((self.upconv4(b), e4), dim=1))
        d3 = self.decoder3(torch.cat((self.upconv3(d4), e3), dim=1))
        d2 = self.decoder2(torch.cat((self.upconv2(d3), e2), dim=1))
        d1 = self.decoder1(torch.cat((self.upconv1(d2), e1), dim=1))
        return torch.sigmoid(self.conv(d1))


def parameter_count(model):
    """Trainable parameters of ``model`` (BatchNorm running statistics are buffers, not
    counted)."""
    return sum(p.numel() for p in model.parameters() if p.requires_grad)


def receptive_radius():
    """Radius (pixels) of the UNet's receptive field around an output pixel, from its
    layers: two 3x3 convolutions per level at scales 1, 2, 4, 8 on the way down, 16 at the
    bottleneck, and 8, 4, 2, 1 on the way up (each adds 1 sample of that scale), plus the
    pooling/upsampling alignment (a 2x2 window at scale s adds up to s/2 ... s on each side).
    Tiled inference uses a halo at least this wide, rounded up to a multiple of 16."""
    r = 0
    for s in (1, 2, 4, 8):        # encoder levels: 2 convs of radius 1 at scale s, then a pool
        r += 2 * s + s            # the 2x2 pool reaches one more sample of scale s
    r += 2 * 16                   # bottleneck
    for s in (8, 4, 2, 1):        # decoder levels: the up-conv (no reach) then 2 convs
        r += 2 * s
    return r
